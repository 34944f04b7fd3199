"""Richardson extrapolation in the element count (mmshbm.analysis.mesh_error): an exact
algebraic series, the beam's linear first frequency against a 8192-element mesh, and the
reasons given where the series is not asymptotic."""

import math

import numpy as np
import pytest

import mmshbm
from mmshbm.analysis.mesh_error import MeshCriteria, mesh_error, observed_order


@pytest.mark.parametrize("p, elements", [(2.0, (8, 16, 32)), (1.3, (5, 9, 21)), (4.0, (4, 6, 9, 13))])
def test_an_exact_algebraic_series_is_recovered(p, elements):
    """f(n) = 3 + 0.7 n^-p: the order and the limit to round-off, any refinement ratios."""
    f = [3.0 + 0.7 * n ** -p for n in elements]
    me = mesh_error(elements, f)
    assert me.asymptotic and me.order == pytest.approx(p, rel=1e-8)
    assert me.extrapolated == pytest.approx(3.0, rel=1e-12)
    assert me.error == pytest.approx(abs(f[-1] / 3.0 - 1), rel=1e-7)


def test_the_beam_linear_frequency_against_a_fine_mesh():
    """The default beam's first linear frequency on 16, 32 and 64 elements (observed order
    ~0.97): the extrapolated value is within 5 % of the 64-element run's true error of the
    8192-element frequency (whose own remaining error is about f(4096) - f(8192) = 2e-3 Hz,
    order 1, 1 % of that true error), and the error estimate matches the true error to 5 %."""
    beam = mmshbm.default_beam()
    elements = (16, 32, 64)
    f = [beam.model(n).linear_frequencies(1)[0] for n in elements]
    f4096, f8192 = (beam.model(n).linear_frequencies(1)[0] for n in (4096, 8192))
    remaining = abs(f4096 - f8192)
    me = mesh_error(elements, f)
    assert me.asymptotic and 0.8 < me.order < 1.2
    true = abs(f[-1] - f8192)
    assert abs(me.extrapolated - f8192) <= 0.05 * true + remaining
    assert me.error * me.extrapolated == pytest.approx(true, rel=0.05)
    assert "mesh error of the 64-element run" in me.describe()


def test_reasons():
    assert mesh_error((8, 16, 32), [1.0, 1.1, 1.05]).reason == "not monotone"
    assert mesh_error((8, 16, 32), [1.0, 1.1, 1.25]).reason == "not contracting"
    # order 0.2 (slow): below the accepted range
    slow = [1 + n ** -0.2 for n in (8, 16, 32)]
    assert mesh_error((8, 16, 32), slow).reason == "order out of range"
    assert mesh_error((8, 16, 32), slow, MeshCriteria(order_range=(0.1, 8))).asymptotic
    # two triples of orders 1 and 3: not yet asymptotic
    n = (4, 8, 16, 32)
    mixed = [1 + n[0] ** -1.0, 1 + n[1] ** -1.0, 1 + n[2] ** -1.0, 1 + n[2] ** -1.0 - (n[2] ** -1.0) * 0.125]
    me = mesh_error(n, mixed)
    assert me.reason == "order inconsistent" and len(me.orders) == 2, me
    assert mesh_error((8, 16), [1.0, 1.1]).reason == "too few meshes"
    assert mesh_error((8, 16, 32), [2.0, 2.0, 2.0]).reason == "converged"
    assert math.isnan(observed_order((8, 16, 32), [1.0, 1.1, 1.05]))
    with pytest.raises(ValueError, match="strictly increasing"):
        mesh_error((16, 8, 32), [1.0, 1.0, 1.0])


def test_nan_runs_are_dropped():
    f = [3.0 + 0.7 * n ** -2.0 for n in (8, 16, 32)]
    me = mesh_error((4, 8, 16, 32), [np.nan, *f])
    assert me.asymptotic and me.elements == (8, 16, 32)

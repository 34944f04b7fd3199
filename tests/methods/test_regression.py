"""Speed work changes no result beyond round-off: backbone frequencies at fixed
amplitudes against values stored from mmshbm at commit b861b41, before the compiled
corrector, the residual step control and accept-by-prediction. The points of a branch may
move (the step control chooses them); the curve may not, so the values are exact points
(``Branch.frequency_at``, pinned Newton to 1e-12) and the tolerance is 1e-9 relative."""

import numpy as np
import pytest

import mmshbm

#: frequency (Hz; the oscillator's in its own units) at amplitude (gaps), computed at b861b41
STORED = {
    ("beam21", "mmshbm", 5): {0.8: 45.814535518422296, 1.5: 54.748593845436936, 3.0: 63.309922254483205,
                              5.0: 67.02234742523807, 10.0: 69.53601777275229},
    ("beam21", "mmshbm", 7): {0.8: 45.81453551842228, 1.5: 55.05617636298281, 2.0: 57.45566260727462,
                              3.0: 64.04787313203566, 5.0: 67.21332126443986, 10.0: 69.61480177784688},
    ("oscillator", "mmshbm", 5): {1.5: 0.17648037280107906, 2.0: 0.18630705789209753,
                                  5.0: 0.20531020394770658},
    ("beam21", "penalty", 5): {1.5: 55.25098382655405, 2.0: 58.77074810095998},
}


def _model(name):
    if name == "beam21":
        return mmshbm.default_beam().model(21)
    return mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()


@pytest.mark.parametrize("key", list(STORED), ids=lambda k: "-".join(map(str, k)))
def test_backbone_equals_the_stored_one(key):
    name, method, H = key
    model = _model(name)
    top = 3.0 if method == "penalty" else max(STORED[key])  # as stored (the points inside are solved)
    b = mmshbm.backbone(model, harmonics=H, method=method, max_amplitude=top * model.gap)
    assert b.status == "bound:amplitude"
    for gaps, f in STORED[key].items():
        got = b.frequency_at(gaps * model.gap, tol=1e-12)
        assert np.isfinite(got), (key, gaps)
        assert abs(got / f - 1) < 1e-9, (key, gaps, got, f)

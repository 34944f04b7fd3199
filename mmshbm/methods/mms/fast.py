"""The data of the compiled corrector (:mod:`mmshbm.methods.mms.corrector_kernels`) for an
MMS-HBM problem: its arguments grouped as the corrector's named tuples."""

from __future__ import annotations

import numpy as np

from ...core.bordered import _SMALL_DENSE
from . import corrector_kernels as ck

__all__ = ["fast_data"]


def fast_data(problem) -> dict | bool:
    """The compiled corrector's data of ``problem`` (an
    :class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`), or False when it does not
    apply (a back end other than the modal one).

    Keys: the named tuples "cond", "scale", "poles", "law", "samples", "work", "ework";
    "fixed" (n_c, H) and "data" (the tuples in the corrector's argument order)."""
    self = problem
    cond = self.cond
    if cond.backend != "modal":
        return False
    from ...harmonic.modal import _POLE_RTOL

    H, n_c, m = self.H, self.n_c, cond.n_modes
    keep = np.ones((H + 1, m), dtype=np.uint8)
    static = np.zeros((H + 1, n_c, n_c))
    if self.n_poles:
        for p, (k, j) in enumerate(self.pole_set.pairs):
            keep[k, j] = 0
            static[k] += np.outer(self.pole_set.b[p], self.pole_set.b[p]) / self.pole_set.omega2[p]
    n = self.n_unknowns
    fast = {
        "cond": ck.ModalCondensation(np.ascontiguousarray(cond.D0), np.ascontiguousarray(cond.b_j),
                                     np.ascontiguousarray(cond._w2), np.ascontiguousarray(cond.Rs), keep,
                                     static, float(_POLE_RTOL)),
        "scale": ck.Scaling(self.colscale, self.rowscale),
        "poles": ck.PoleTerms(self._pole_k, self._pole_b, self._pole_w2),
        "law": ck.ContactLaw(self.cdof, self.lo, self.hi, self.r_each, self.projection == "exact"),
        "samples": ck.Sampling(self._cos_table, self._sin_table, self._tau),
        "work": ck.NewtonWork(np.empty((H + 1, n_c, n_c)), np.empty((H + 1, n_c, n_c)), np.empty(n - 1),
                              np.empty((n - 1, n)), np.empty((n, n)), np.empty(n), np.empty((n, n)),
                              np.empty(n), np.empty((H + 1, n_c)), np.empty(self.n_poles), np.zeros(1),
                              # the tangent solve where the continuation's is the same LU
                              np.empty(n if n <= _SMALL_DENSE else 0), np.zeros(1), np.zeros(1)),
        "ework": ck.EvalWork(*self._work),
    }
    # the arguments after (u, u_pred, t, tol, step_tol, max_iter) that do not change
    fast["fixed"] = (int(self.n_c), int(self.H))
    fast["data"] = tuple(fast[k] for k in ("scale", "cond", "poles", "law", "samples", "work", "ework"))
    return fast

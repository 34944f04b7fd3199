"""``backbone(model, tol=1e-4)`` against a fixed H = 31 on two chains with stiff contacts
(``validation.corpus_exact.chains(100, seed=3, max_masses=3, contact_decades=(0, 6))``,
to 1.56 gaps): #9, whose contact the default cap of 64 harmonics resolves (tol met), and
#32, whose contact rings ~110 times faster than the orbit (tol out of reach: the run
keeps its best solves and says so). The ratio time_tolerance / time_fixed_31 is the cost
of asking for accuracy (docs/accuracy.md). Kernels are compiled in ``setup``."""

from __future__ import annotations

import warnings

_CHAINS = {"resolved": 9, "unresolved": 32}


def _model(which: str):
    from validation.corpus_exact import chains

    return chains(_CHAINS[which] + 1, seed=3, max_masses=3, contact_decades=(0, 6))[_CHAINS[which]].model()


def _run(model, **kwargs):
    from mmshbm.methods.backbone import backbone

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return backbone(model, max_amplitude=1.56 * model.gap, **kwargs)


class ToleranceBackbone:
    params = [list(_CHAINS)]
    param_names = ["chain"]
    number = 1
    repeat = (1, 5, 30.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self, which):
        self.model = _model(which)
        _run(self.model, harmonics=8)  # compiles the kernels
        _run(self.model, tol=1e-2, max_harmonics=16)

    def time_tolerance(self, which):
        _run(self.model, tol=1e-4)

    def time_fixed_31(self, which):
        _run(self.model, harmonics=31)

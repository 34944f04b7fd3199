"""Time-domain shooting baselines: the massless contact node's exact law per time step.

The conservative backbone (:mod:`.conservative`), forced responses (:mod:`.forced`),
friction alone (:mod:`.friction`) and impact with friction (:mod:`.friction_impact`; several
contacts marched to steady state in :mod:`.friction_march`); the compiled integrators in
:mod:`._kernels`, :mod:`._contact_kernels`, :mod:`._forced_kernels` and
:mod:`._march_kernels`, their time signals in :mod:`.signals`.

``mmshbm.methods.shooting`` was the conservative module before the methods were grouped;
its names are still found here (loaded on first use).
"""


def __getattr__(name: str):
    if name.startswith("__"):
        raise AttributeError(name)
    import importlib

    conservative = importlib.import_module(__name__ + ".conservative")
    try:
        return getattr(conservative, name)
    except AttributeError:
        raise AttributeError(f"module 'mmshbm.methods.shooting' has no attribute {name!r}") from None

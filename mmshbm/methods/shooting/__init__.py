"""Time-domain shooting baselines: the massless contact node's exact law per time step.

The conservative backbone (:mod:`.conservative`), forced responses (:mod:`.forced`),
friction alone (:mod:`.friction`) and impact with friction (:mod:`.friction_impact`; several
contacts marched to steady state in :mod:`.friction_march`); the compiled integrators in
:mod:`._kernels`, :mod:`._contact_kernels`, :mod:`._forced_kernels` and
:mod:`._march_kernels`, their time signals in :mod:`.signals`.
"""

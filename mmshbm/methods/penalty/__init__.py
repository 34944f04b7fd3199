"""Penalty-HBM baselines: the contact as a stiff spring, the harmonics by AFT.

The full-order backbone (:mod:`.hbm`; its Jacobian's pattern in :mod:`.assembly`, its
signals in :mod:`.signals`, the default samples and contact stiffness in :mod:`.defaults`),
the same on the Craig–Bampton reduction (:mod:`.reduced`), forced responses
(:mod:`.forced`) and the Jenkins element for friction (:mod:`.jenkins`); the compiled AFT
loops in :mod:`._kernels` and :mod:`._reduced_kernels`.
"""

"""The methods: MMS-HBM, the penalty-HBM and shooting baselines, the exact reference,
and :func:`~mmshbm.methods.backbone.backbone`, the one entry point for all of them.

Importing the package registers the functions the results call
(:mod:`mmshbm.methods.entry_points`)."""

from . import entry_points  # noqa: F401 - registers with mmshbm.results.base

"""The methods: MMS-HBM, the penalty-HBM and shooting baselines, the exact reference,
and :func:`~mmshbm.methods.backbone.backbone`, the one entry point for all of them."""

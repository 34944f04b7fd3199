"""What the methods produce: :class:`~mmshbm.results.branch.Branch` and its file format."""

"""The validation harness of mmshbm: measurements of the library, not part of it (the
installed package is ``mmshbm`` alone).

* :mod:`validation.corpus`: the default backbone on random structures (completion);
* :mod:`validation.corpus_exact`: the default backbone against exact periodic orbits;
* :mod:`validation.throughput`: backbones per second of a Monte-Carlo study per executor;
* :mod:`validation.asv_tables`: the benchmark tables of a recorded asv run;
* :mod:`validation.tables`: every table of docs/validation.md from the runs.

Run from the repository root: ``python -m validation {corpus,exact,throughput,tables} ...``
(docs/validation.md).
"""

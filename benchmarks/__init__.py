"""airspeed velocity benchmarks of mmshbm (see docs/benchmarks.md).

Suites by concern: :mod:`.common` (models, references, skips, warm-up), kernels and
transforms, one Newton iteration and one corrector step per method, whole backbones
(time and peak memory), and tracked accuracy, Newton iterations and continuation steps.
"""

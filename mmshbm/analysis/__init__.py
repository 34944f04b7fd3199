"""Analyses built on the methods: convergence studies, benchmarks, identification from
measurements."""

"""The package's BLAS thread limit (mmshbm._threads): one thread by default, the user's
choice respected."""

import numpy as np  # noqa: F401  (its BLAS library loaded)
import pytest
import scipy.linalg  # noqa: F401
from threadpoolctl import threadpool_info

from mmshbm import _threads


def _blas_threads() -> set[int]:
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


@pytest.fixture
def clean_env(monkeypatch):
    for name in (*_threads.BLAS_ENV, "MMSHBM_BLAS_THREADS"):
        monkeypatch.delenv(name, raising=False)
    return monkeypatch


def test_one_thread_inside_and_restored_after(clean_env):
    before = {lib["filepath"]: lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    assert before  # numpy's and scipy's BLAS
    with _threads.blas_limit():
        assert _blas_threads() == {1}
    after = {lib["filepath"]: lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    assert after == before


def test_the_users_choice_is_kept(clean_env):
    clean_env.setenv("OPENBLAS_NUM_THREADS", "2")
    before = _blas_threads()
    with _threads.blas_limit():
        assert _blas_threads() == before
    clean_env.delenv("OPENBLAS_NUM_THREADS")
    clean_env.setenv("MMSHBM_BLAS_THREADS", "1")
    with _threads.blas_limit():
        assert _blas_threads() == {1}
    clean_env.setenv("MMSHBM_BLAS_THREADS", "two")
    with pytest.raises(ValueError, match="MMSHBM_BLAS_THREADS must be a positive integer, got 'two'"):
        _threads.blas_limit()


def test_single_thread_env(clean_env):
    _threads.single_thread_env()
    assert all(_threads.os.environ[name] == "1" for name in _threads.BLAS_ENV)
    clean_env.setenv("MKL_NUM_THREADS", "4")
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS"):
        clean_env.delenv(name)
    _threads.single_thread_env()  # the user set one: nothing changes
    assert "OPENBLAS_NUM_THREADS" not in _threads.os.environ

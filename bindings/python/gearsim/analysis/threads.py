"""One BLAS thread for the analysis' own linear algebra.

The fits and the screening solve many small least-squares problems (tens of
thousands of rows, a handful of columns) between simulations. A threaded
BLAS gains nothing on problems that size, and on a machine whose cores are
busy its threads wait for each other: a dot product of 58 000 numbers took
0.4 ms with OpenBLAS's default threads on the 2-core reference machine under
load and 0.009 ms with one. diagnose, fit, refit and the report's rounds run
under :func:`one_blas_thread` (threadpoolctl, of the analysis extra; without
it nothing is limited)."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

__all__ = ["one_blas_thread", "single_blas_thread"]

F = TypeVar("F", bound=Callable[..., Any])


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit the BLAS thread pools to one thread inside the block."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with the analysis extra
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def single_blas_thread(fn: F) -> F:
    """Decorator: fn runs under one_blas_thread."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with one_blas_thread():
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]

"""One BLAS thread for the small matrices of a (re)linearisation.

The tiers build their propagators from matrix exponentials and solves of 10-22 rows (scipy's
``expm``, numpy's ``inv`` and ``@``), at set-up and whenever the load moves by more than 20 %
(a rotating unbalance does that at every batch).  OpenBLAS runs such calls on all cores, and its
threads spin while they wait: on the 2-core CI machine with another process busy, one
relinearisation took 20-50 ms instead of ~1 ms (a 10 ms batch of the live node overran), and
even idle its CPU time doubled.  numpy and scipy each bring their own OpenBLAS, so an environment
variable set after their import does not reach both; ``threadpoolctl`` limits every BLAS loaded
in the process, for the duration of a ``with`` block only, so a caller's own numpy work keeps its
threads.
"""
from __future__ import annotations

import contextlib

_controller = None


def single_threaded_blas():
    """A context in which every BLAS library loaded in the process (numpy's and scipy's) runs on
    one thread.  Without ``threadpoolctl`` installed (an apt workspace without
    python3-threadpoolctl) a no-op."""
    global _controller
    if _controller is None:
        try:
            import scipy.linalg  # noqa: F401 - loads scipy's BLAS, so that the controller sees it
            from threadpoolctl import ThreadpoolController
        except ImportError:
            return contextlib.nullcontext()
        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")

"""One BLAS thread while identifying (:mod:`pkdyn.threads`, kept here for its importers)."""

from pkdyn.threads import single_blas_thread

__all__ = ["single_blas_thread"]

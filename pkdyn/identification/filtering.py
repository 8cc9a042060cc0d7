"""Velocities and accelerations from measured positions: zero-phase low-pass, then differences.

Encoders give positions; differentiating them twice amplifies their noise by ``(2 pi f)^2``.
The positions are first filtered by a Butterworth low-pass run forwards and backwards
(``scipy.signal.sosfiltfilt``: no phase lag, squared magnitude response), then differentiated
by second-order central differences (``numpy.gradient``). The cut-off should sit well above
the motion's bandwidth (a few times its highest harmonic) and below the noise: the default,
:data:`DEFAULT_CUTOFF_RATIO` of the sampling rate, suits a 1 kHz encoder and a 10-20 Hz
excitation. Uniform sampling is required.
"""

from __future__ import annotations

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["DEFAULT_CUTOFF_RATIO", "derivatives"]

DEFAULT_CUTOFF_RATIO = 0.05
"""Default cut-off frequency as a fraction of the sampling rate (50 Hz at 1 kHz)."""

_ORDER = 4


def derivatives(
    t: np.ndarray, qa: np.ndarray, cutoff: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filtered positions, rates and accelerations of uniformly sampled positions.

    Args:
        t: Times (N,) [s], uniformly spaced.
        qa: Positions (N, n) [rad or m].
        cutoff: Cut-off frequency [Hz] (default :data:`DEFAULT_CUTOFF_RATIO` x sampling rate).

    Returns:
        ``(qa_filtered, qa_dot, qa_ddot)``, each (N, n).

    Raises:
        InvalidInputError: Non-uniform sampling, too few samples for the filter, or a cut-off
            outside ``(0, Nyquist)``.

    """
    from scipy.signal import butter, sosfiltfilt

    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    h = float(np.mean(dt))
    if np.max(np.abs(dt - h)) > 1e-3 * h:
        raise InvalidInputError(
            "t",
            "filtering the positions needs uniform sampling; give the qa_dot_* and qa_ddot_* "
            "columns instead",
        )
    fs = 1.0 / h
    fc = DEFAULT_CUTOFF_RATIO * fs if cutoff is None else float(cutoff)
    if not 0.0 < fc < 0.5 * fs:
        raise InvalidInputError(
            "cutoff", f"{fc:g} Hz must lie in (0, {0.5 * fs:g}) Hz (half the sampling rate)"
        )
    duration = float(t[-1] - t[0])
    if fc * duration < 1.0:  # below one period over the record: the filter leaves no motion
        raise InvalidInputError(
            "cutoff",
            f"{fc:g} Hz is below 1 / duration = {1.0 / duration:g} Hz: the filter would remove "
            f"the whole {duration:g} s motion; give a cut-off above the motion's frequencies",
        )
    sos = butter(_ORDER, fc, fs=fs, output="sos")
    pad = 3 * (2 * sos.shape[0] + 1)
    if t.size <= pad:
        raise InvalidInputError("data", f"{t.size} samples: the filter needs more than {pad}")
    try:
        qf = sosfiltfilt(sos, qa, axis=0)
    except np.linalg.LinAlgError:  # a filter too narrow for the floating point
        raise InvalidInputError(
            "cutoff", f"{fc:g} Hz is too low a cut-off for samples at {fs:g} Hz"
        ) from None
    qd = np.gradient(qf, h, axis=0)
    qdd = np.gradient(qd, h, axis=0)
    return qf, qd, qdd

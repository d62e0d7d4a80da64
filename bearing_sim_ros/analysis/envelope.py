"""Envelope analysis: the standard bearing-fault detector, shared by tests, the monitor node,
reports and the CWRU validation so that every verdict comes from the same code.

Recipe (PHYSICS_NOTES): band-pass around the structural resonance (2-5 kHz by default), Hilbert
envelope, spectrum of the envelope, and at each fault frequency the height of the line against
the median level of its neighbourhood.

Choices, checked on the CWRU recordings (``bearing-sim validate``, README "Validation against real recordings"):

* Band 2-5 kHz (clipped below 0.9 x Nyquist) wherever it serves the lines judged
  (:func:`detector_band`: its low edge and its width at least the envelope spectrum's span,
  1.2 x the highest fault line + 40 Hz), else moved up above them, or no verdict where no band
  fits below Nyquist.  The CWRU housing resonances that the defect
  impacts ring sit at 2.3-3.6 kHz (plus 5.2 kHz for the outer-race fault); the healthy machine's
  lines in the band (near 4.1 kHz) beat at 120 and 240 Hz, away from every fault line.  A band
  picked by spectral kurtosis was tried and rejected:
  on the real recordings the impacts overlap (one every 6-9 ms, rings of several ms), spectral
  kurtosis stays below 1.5 in every band and its maximum lands on noise.
* Averaged envelope spectrum (Welch, ``segment`` = 1 s, Hann, 50 % overlap) for the decision.
  A line's amplitude does not depend on the resolution but the noise floor per bin does, so the
  prominence of a single long FFT grows with the record length and a fixed threshold would
  mean different false-alarm rates for 1 s and 20 s.  Averaging fixes the resolution at 1 Hz and
  makes the floor's median a steady reference.  Largest score of white noise: 3.4 over 150
  one-second records, 1.8 over 150 four-second ones.  CWRU recordings, any 1 s window: healthy
  <= 2.8, inner race 44-62 (BPFI), outer race 68-129 (BPFO); threshold 4.
* Below FTF = 8 Hz (about 1200 rpm on the ER-16K and the 6205) segments of 8 cage turns
  instead (:func:`decision_segment`): there 1 Hz bins merge a fault line with its cage- and
  shaft-rate sidebands and a ball or inner pit at 300 rpm scored x1.6-2.1
  (docs/low_speed_detection.md).  A record shorter than that is one FFT (white noise: up to 3.6
  over 4 s at 300 rpm, as over a 1 s record).
* One line per fault (no harmonic sum): 3 x BPFO and 2 x BPFI of the 6205 lie 0.7 % apart, and
  summing harmonics made an outer-race fault score for "inner" too.
* A fault's line that sits on another detected fault's sideband is that fault's
  (:func:`borrowed_lines`): the inner pit's shaft-rate sidebands and the ball pit's cage-rate
  ones fall on each other's lines at some speeds and skids (docs/detector_confusion.md).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import UserError, short_repr

DEFAULT_BAND = (2000.0, 5000.0)
DEFAULT_SEGMENT = 1.0     # s: length of the averaged segments of the detector's envelope spectrum
# how ``detector_band``'s one line begins where no band serves the lines
NO_BAND = "no envelope band"


class NoBand(str):
    """``detector_band``'s reason where no band serves the fault lines: one line, beginning with
    ``NO_BAND``, whose type says so where a caller passes reasons on as text (``orders.
    order_diagnose``'s ``(None, why not)``): the monitor counts those windows apart from the ones
    whose lines moved, without reading the words."""
# segments span at least this many cage turns (decision_segment): a ball pit meets the load zone
# once per cage turn and the others' lines carry the cage or shaft rate as sidebands, which bins of
# 1 Hz merge with the line below about 1000 rpm (the ER-16K's FTF 6.6 Hz); 1/8 of FTF apart, the
# first sidebands lie 8 bins off, clear of the Hann main lobe (+-2 bins) and the +-1 % search
CAGE_TURNS = 8.0
FAULT_KEYS = ("ftf", "bpfo", "bpfi", "bsf")   # what Bearing.fault_frequencies gives, Hz
FAULT_LINES = {          # which envelope line marks which fault
    "outer": "bpfo",
    "inner": "bpfi",
    "ball": "2bsf",
    "cage": "ftf",
}
LINE_LABELS = {"bpfo": "BPFO", "bpfi": "BPFI", "2bsf": "2xBSF", "ftf": "FTF"}   # each line's name in words


def one_channel(x) -> np.ndarray:
    """``x`` as a float array of one channel's samples; anything else (a batch's whole ``accel``,
    (n, 2)) is a one-line :class:`~bearing_sim_ros.errors.UserError`: the filters ran along the
    wrong axis (scipy's "padlen" error) and the statistics mixed both channels."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1:
        raise UserError(f"x: an array of shape {x.shape}: expected one channel, a 1-D array of samples "
                        "(e.g. batch.accel[:, 1])")
    return x


def envelope_band(fs: float, band=DEFAULT_BAND) -> tuple:
    """(low, high) Hz: the band-pass of the envelope at the sample rate ``fs`` (Hz): ``band``
    with its top held to 0.9 x Nyquist and its bottom to half its top (1 kHz: 225-450 Hz)."""
    lo, hi = band
    nyq = 0.5 * fs
    hi = min(hi, 0.9 * nyq)
    lo = min(lo, 0.5 * hi)
    return lo, hi


def spectrum_span(frequencies: Mapping, neighbourhood_hz: float = 20.0) -> float:
    """The top (Hz) of the envelope spectrum the detector reads for ``frequencies``
    (``Bearing.fault_frequencies``, Hz): 1.2 x its highest line (:func:`fault_targets`: BPFO,
    BPFI, 2xBSF, FTF) plus two neighbourhoods of ``neighbourhood_hz``: each line's +-1 % search
    with room for a cage skid or a ball slip, and the +-``neighbourhood_hz`` it is compared with."""
    return 1.2 * max(fault_targets(frequencies).values()) + 2 * neighbourhood_hz


def detector_band(frequencies: Mapping, fs: float, resonance_hz: float | None = None,
                  neighbourhood_hz: float = 20.0) -> tuple:
    """The band-pass (Hz) of the envelope for the fault lines of ``frequencies`` (Hz) at the
    sample rate ``fs`` (Hz): ``((low, high), "")``, or ``(None, why)`` where none fits.

    The rule, with ``span`` = :func:`spectrum_span` (the top of the envelope spectrum read):

    * the low edge at least ``span``: no line the detector reads is in the band as a carrier.
      Bands near the lines misread inner pits: the ER-16K's at 4000 rpm at 15 kHz is "outer" in
      0.9-1.8 kHz (BPFO x78, BPFI x25: BPFO = Z x shaft - BPFI, the pit's own line family),
      "inner" in 2-5 kHz (x10, x91; docs/envelope_band.md);
    * the width at least ``span`` (from ``span`` up, an octave): the envelope of a band-limited
      signal holds the differences of the frequencies in the band, up to its width;
    * the top at most 0.9 x Nyquist (:func:`envelope_band`).

    The default band as :func:`envelope_band` clips it (2-5 kHz from 11.1 kHz of sample rate,
    225-450 Hz at 1 kHz) wherever it keeps the rule: up to a highest line of 1633 Hz from
    11.1 kHz up (the ER-16K to 18 000 rpm, the 6205 to 11 000 rpm), of 154 Hz at 1 kHz.  Else
    the band moves up: from ``span``, its top the largest of the default's (5 kHz), 2 x ``span``
    and 1.25 x ``resonance_hz`` (the structure's resonator, Hz, where known and above ``span``:
    the ring the impacts excite; the ER-16K's inner pit read "outer" in bands without its
    3.8 kHz resonator), held under 0.9 x Nyquist.  Where that leaves it narrower than ``span``
    there is none: the lines lie too close to Nyquist (a 6000-size bearing at 40 000 rpm, BPFI
    2.95 kHz, at 15 kHz: a band from 3.58 kHz 3.58 kHz wide needs a sample rate of 15.9 kHz)."""
    span = spectrum_span(frequencies, neighbourhood_hz)
    lo, hi = envelope_band(fs)
    if lo >= span and hi - lo >= span:
        return (lo, hi), ""
    top = 0.9 * 0.5 * fs
    lo = max(lo, span)
    want = max(DEFAULT_BAND[1], lo + span)     # lo = span here or above: at least an octave
    if resonance_hz is not None and np.isfinite(resonance_hz) and resonance_hz > lo:
        want = max(want, 1.25 * float(resonance_hz))
    hi = min(want, top)
    if hi - lo >= span:
        return (lo, hi), ""
    f_top = max(fault_targets(frequencies).values())
    return None, NoBand(f"{NO_BAND}: the fault lines judged reach {f_top:.0f} Hz, and the envelope spectrum read "
                        f"up to {span:.0f} Hz needs a band from {span:.0f} Hz at least {span:.0f} Hz wide, above 0.9 x "
                        f"Nyquist ({top:.0f} Hz at {fs:g} Hz): no verdict (a sample rate of at least "
                        f"{4 * span / 0.9:.0f} Hz gives one)")


def band_words(band) -> str:
    """The envelope band ``band`` ((low, high) Hz) in words: ``2-5 kHz``, ``0.225-0.45 kHz``."""
    lo, hi = band
    return f"{lo / 1e3:.3g}-{hi / 1e3:.3g} kHz"


def envelope(x: np.ndarray, fs: float, band=DEFAULT_BAND) -> np.ndarray:
    """Hilbert envelope of ``x`` band-passed to ``band`` (Hz), mean removed."""
    from scipy.signal import butter, hilbert, sosfiltfilt

    x = one_channel(x)
    lo, hi = envelope_band(fs, band)
    sos = butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos")
    y = sosfiltfilt(sos, x - x.mean())
    env = np.abs(hilbert(y))
    return env - env.mean()


def envelope_spectrum(x: np.ndarray, fs: float, band=DEFAULT_BAND, max_freq: float = 1000.0,
                      segment: float | None = None):
    """(freqs Hz, amplitude) of the envelope spectrum up to ``max_freq``, Hann window,
    amplitude-corrected (a sinusoidal envelope component of amplitude a shows as a, in the units
    of ``x``).

    segment: None = one FFT of the whole record (finest resolution, for plots); a duration (s)
    = the RMS average of Hann segments of that length with 50 % overlap (Welch), resolution
    1 / segment, the floor's variance reduced by the number of segments (for decisions)."""
    return averaged_spectrum(envelope(x, fs, band), fs, max_freq, segment)


def averaged_spectrum(env: np.ndarray, rate: float, max_freq: float, segment: float | None = None):
    """(freqs, amplitude) of ``env`` (an envelope, sampled ``rate`` times per unit: per second,
    or per shaft revolution for order tracking, ``analysis.orders``) up to ``max_freq`` (per
    unit: Hz, or orders), as :func:`envelope_spectrum` computes it (``segment``: in the same
    unit, s or revolutions)."""
    n = env.size
    nseg = _segment_samples(n, rate, segment)
    win = np.hanning(nseg)
    if nseg == n:
        spec = np.abs(np.fft.rfft(env * win))
    else:
        step = nseg // 2
        starts = range(0, n - nseg + 1, step)
        power = np.zeros(nseg // 2 + 1)
        for s in starts:
            seg = env[s:s + nseg]
            power += np.abs(np.fft.rfft((seg - seg.mean()) * win)) ** 2
        spec = np.sqrt(power / len(starts))
    spec *= 2.0 / win.sum()
    freqs = np.fft.rfftfreq(nseg, 1.0 / rate)
    keep = freqs <= max_freq
    return freqs[keep], spec[keep]


def decision_segment(frequencies: Mapping, segment: float = DEFAULT_SEGMENT) -> float:
    """The detector's segment (s, or revolutions where ``frequencies`` are orders): ``segment``, or
    ``CAGE_TURNS`` cage turns (``frequencies["ftf"]``, per the same unit) where that is longer.

    At 300 rpm the ER-16K's cage turns at 2 Hz and a ball pit's 2xBSF line carries sidebands every
    2 Hz (the pit passes the load zone once per cage turn), an inner pit's BPFI every 5 Hz (once per
    shaft turn): 1 s segments (1 Hz bins, the Hann main lobe +-2 Hz) smear them into one hump that
    the +-20 Hz floor rises with, and a 0.6 mm ball pit scored x2.1 (kinematic) and x1.6 (skidding)
    over 4 s, an inner pit x1.8 and x2.0 (docs/low_speed_detection.md).  Segments of 8 cage turns
    (4 s there) resolve the line: x9.6 / x18.3, x16.7 / x23.5.  From 1200 rpm up on the ER-16K (and
    the CWRU 6205 at 1797 rpm: FTF 11.9 Hz) this is 1 s: nothing changes there."""
    ftf = frequencies.get("ftf", 0.0) if isinstance(frequencies, Mapping) else 0.0
    try:
        ftf = abs(float(ftf))
    except (TypeError, ValueError):
        ftf = 0.0
    return max(segment, CAGE_TURNS / ftf) if np.isfinite(ftf) and ftf > 0 else segment


def _segment_samples(n: int, fs: float, segment: float | None) -> int:
    """Samples per FFT of :func:`envelope_spectrum` for a record of ``n`` samples."""
    return n if segment is None else max(16, min(n, int(round(segment * fs))))


def shortest_record_s(neighbourhood_hz: float = 20.0) -> float:
    """The shortest record (and ``segment``), s, whose envelope spectrum leaves every line a
    neighbourhood of +-``neighbourhood_hz`` to be compared with: bins ``neighbourhood_hz`` / 4
    apart (0.2 s for 20 Hz).  :func:`line_at` leaves out its search window (at least 1.5 bins)
    and two bins more on either side, so coarser bins leave none."""
    return 4.0 / neighbourhood_hz


def _too_short(n: int, fs: float, segment: float | None, neighbourhood_hz: float) -> str:
    """Why a record of ``n`` samples at ``fs`` Hz is too short for the lines' neighbourhoods (with
    ``segment``), or ""."""
    nseg = _segment_samples(n, fs, segment)
    shortest = shortest_record_s(neighbourhood_hz)
    if nseg >= shortest * fs - 1e-9:
        return ""
    what = (f"segment = {segment:g} s" if nseg < n else f"x = {n} samples ({n / fs:g} s at {fs:g} Hz)")
    return (f"{what}: too short for the envelope detector: its spectrum's bins {fs / nseg:.3g} Hz apart leave a "
            f"line no +-{neighbourhood_hz:g} Hz neighbourhood to be compared with; give at least {shortest:g} s")


@dataclass
class Line:
    """One envelope line: where it was found, its height and its height over the local median."""

    expected_hz: float
    found_hz: float
    height: float
    prominence: float     # height / median of the neighbourhood (dimensionless)


def line_at(freqs: np.ndarray, spec: np.ndarray, f0: float, search_rel: float = 0.01,
            neighbourhood_hz: float = 20.0) -> Line:
    """The largest line within +-``search_rel`` of ``f0`` and its prominence over the median of
    the spectrum in +-``neighbourhood_hz`` around it (the search window and two bins excluded;
    where they fill it, the ``neighbourhood_hz`` beyond them).  The prominence is NaN where that
    holds no bin (bins as coarse as it) and 0 where the spectrum is 0 there (a flat signal has
    no lines)."""
    df = freqs[1] - freqs[0]
    tol = max(search_rel * f0, 1.5 * df)
    sel = np.flatnonzero(np.abs(freqs - f0) <= tol)
    if sel.size == 0:
        return Line(f0, float("nan"), 0.0, 0.0)
    k = sel[np.argmax(spec[sel])]
    # parabolic interpolation of the peak on the log spectrum for a sub-bin frequency, at a local
    # maximum only (then within half a bin): the largest bin of the search window may sit on its
    # edge, on a slope rising beyond it, where the parabola's vertex can lie anywhere (784 Hz for a
    # BPFI of 162 Hz, its neighbourhood then empty and the prominence infinite)
    fk = freqs[k]
    if (0 < k < spec.size - 1 and spec[k - 1] > 0 and spec[k + 1] > 0 and spec[k] > 0
            and spec[k] >= spec[k - 1] and spec[k] >= spec[k + 1]):
        a, b, c = np.log(spec[k - 1]), np.log(spec[k]), np.log(spec[k + 1])
        denom = a - 2 * b + c
        if denom < 0:
            fk = freqs[k] + 0.5 * (a - c) / denom * df
    near = np.abs(freqs - fk)
    ring = (near <= neighbourhood_hz) & (near > tol + 2 * df)
    if not ring.any():
        # a search window (+-search_rel) that fills the neighbourhood, a line above about 1.8 kHz:
        # the neighbourhood's width beyond it (there was no bin, an infinite prominence)
        ring = (near <= tol + 2 * df + neighbourhood_hz) & (near > tol + 2 * df)
    median = float(np.median(spec[ring])) if ring.any() else float("nan")
    # not a number where there is nothing to compare with (it was infinite, and every line of a
    # record too short for its neighbourhood a fault); 0 / 0 (a flat signal: no line, no floor)
    # is no line, where it was an infinite one
    if median > 0:
        prominence = float(spec[k] / median)
    elif not ring.any():
        prominence = float("nan")
    else:
        prominence = float("inf") if spec[k] > 0 else 0.0
    return Line(f0, float(fk), float(spec[k]), prominence)


def fault_targets(frequencies: dict) -> dict:
    """The envelope lines to look at (Hz): "bpfo", "bpfi", "2bsf" (a ball defect strikes both
    races once per spin turn), "ftf"."""
    if not (isinstance(frequencies, Mapping) and all(k in frequencies for k in FAULT_KEYS)):
        raise UserError(f"frequencies = {short_repr(frequencies)}: expected the fault frequencies in Hz, a mapping "
                        f"with {', '.join(FAULT_KEYS)} (Bearing.fault_frequencies, Scene.fault_frequencies)")
    return {"bpfo": frequencies["bpfo"], "bpfi": frequencies["bpfi"],
            "2bsf": 2.0 * frequencies["bsf"], "ftf": frequencies["ftf"]}


def fault_lines(x: np.ndarray, fs: float, frequencies: dict, band="auto",
                neighbourhood_hz: float = 20.0, search_rel: float = 0.01,
                segment: float | None | str = "auto", resonance_hz: float | None = None) -> dict:
    """Envelope lines at the fault frequencies, on the averaged envelope spectrum
    (``segment`` s, see :func:`envelope_spectrum`; "auto": :func:`decision_segment`, 1 s or
    ``CAGE_TURNS`` cage turns where those are longer; a record shorter than that is one FFT).

    ``frequencies``: ``{"ftf", "bpfo", "bpfi", "bsf"}`` in Hz (``Bearing.fault_frequencies``).
    ``band``: the band-pass (low, high) Hz, or "auto": :func:`detector_band` of these lines
    (2-5 kHz wherever that serves them; ``resonance_hz``: the structure's resonator, Hz, where
    known).  Returns ``{name: Line}`` for "bpfo", "bpfi", "2bsf", "ftf".  A record (or
    ``segment``) shorter than :func:`shortest_record_s`, whose bins leave a line no
    neighbourhood, or lines with no band ("auto"), is a one-line
    :class:`~bearing_sim_ros.errors.UserError`.
    """
    x = one_channel(x)
    targets = fault_targets(frequencies)
    if isinstance(segment, str) and segment == "auto":
        segment = decision_segment(frequencies)
    reason = _too_short(x.size, fs, segment, neighbourhood_hz)
    if reason:
        raise UserError(reason)
    if isinstance(band, str) and band == "auto":
        band, reason = detector_band(frequencies, fs, resonance_hz, neighbourhood_hz)
        if band is None:
            raise UserError(reason)
    fmax = spectrum_span(frequencies, neighbourhood_hz)
    freqs, spec = envelope_spectrum(x, fs, band, max_freq=fmax, segment=segment)
    return {name: line_at(freqs, spec, f0, search_rel, neighbourhood_hz) for name, f0 in targets.items()}


DETECTION_THRESHOLD = 4.0   # prominence (line over local median) that counts as a detected fault
# relative spread of the fault lines' frequencies (= of the shaft and cage speeds) over a record
# beyond which a line leaves the +-1 % search of line_at (search_rel) in part of it: its envelope
# spectrum smears the line, and a verdict on it is no verdict (a speed step, a ramp, a load step
# that changes the cage's skid)
STEADY_LINES = 0.01


def spread(values) -> float:
    """How far ``values`` (speeds sampled evenly over a record) move, relative: the width of
    their middle 90 % (5th to 95th percentile) over |mean| (dimensionless); 0 for none or a mean
    of 0.  The middle: a transient of a few tens of ms smears no line (the skidding tier's cage
    settles from pure rolling, 1 %, in its first 20 ms), and the largest minus the smallest
    made a steady record's first second "unknown"."""
    values = np.asarray(values, dtype=float)
    if not values.size or not np.all(np.isfinite(values)) or values.mean() == 0.0:
        return 0.0
    low, high = np.percentile(values, [5.0, 95.0])
    return float((high - low) / abs(values.mean()))


def with_cage(frequencies: dict, balls: int, shaft_hz: float, cage_hz: float) -> dict:
    """``frequencies`` (``Bearing.fault_frequencies``, Hz) with the cage, BPFO and BPFI of the
    cage speed ``cage_hz`` (Hz) as it ran: FTF = cage_hz, BPFO = Z cage_hz, BPFI = Z (shaft_hz -
    cage_hz), Z = ``balls``.  Where the cage skids (7 % at 10000 rpm / 10 N on the ER-16K) the
    lines are there, not at pure rolling; BSF (the balls' spin) stays as given."""
    ftf = abs(cage_hz)
    return {**frequencies, "ftf": ftf, "bpfo": balls * ftf, "bpfi": balls * abs(abs(shaft_hz) - ftf)}


def diagnose(x: np.ndarray, fs: float, frequencies: dict, band="auto",
             threshold: float = DETECTION_THRESHOLD, segment: float | None | str = "auto",
             resonance_hz: float | None = None) -> dict:
    """Envelope verdict: ``{"verdict": "healthy" | "outer" | "inner" | "ball", "lines": {...},
    "scores": {fault: prominence}, "borrowed": {fault: (other fault, k)}, "band": (low, high)
    Hz}``.  The fault whose line stands highest above ``threshold`` wins, unless that line is
    another detected fault's sideband (``borrowed``, :func:`borrowed_lines`); none above it is
    "healthy".  ``band`` ("auto": :func:`detector_band`), ``segment``, ``resonance_hz``: see
    :func:`fault_lines`.  Where no band serves the lines: ``{"verdict": "unknown", "band": None,
    "no_band": why (one line), "lines": {}, "scores": {}, "borrowed": {}}``."""
    if isinstance(band, str) and band == "auto":
        band, why = detector_band(frequencies, fs, resonance_hz)
        if band is None:
            return {"verdict": "unknown", "band": None, "no_band": why, "lines": {}, "scores": {}, "borrowed": {}}
    result = verdict_of(fault_lines(x, fs, frequencies, band, segment=segment), threshold)
    return {**result, "band": envelope_band(fs, band)}


def verdict_of(lines: dict, threshold: float = DETECTION_THRESHOLD) -> dict:
    """:func:`diagnose`'s result from the fault ``lines`` ({"bpfo", "bpfi", "2bsf", "ftf": Line},
    in Hz or in orders alike), with ``"borrowed"`` (:func:`borrowed_lines`): the highest line
    over ``threshold`` that is not another detected fault's sideband wins."""
    scores = {fault: lines[key].prominence for fault, key in FAULT_LINES.items() if fault != "cage"}
    borrowed = borrowed_lines(lines, threshold)
    return {"verdict": pick_verdict(scores, borrowed, threshold), "lines": lines, "scores": scores,
            "borrowed": borrowed}


def pick_verdict(scores: dict, borrowed, threshold: float = DETECTION_THRESHOLD) -> str:
    """The fault of the highest of ``scores`` ({fault: prominence}) at or over ``threshold`` that is
    not in ``borrowed`` (faults whose line is another's sideband); where every one over it is, the
    highest of them; "healthy" where none is over it."""
    over = [fault for fault in scores if scores[fault] >= threshold]
    own = [fault for fault in over if fault not in borrowed] or over
    return max(own, key=scores.get) if own else "healthy"


# Sidebands by which a detected fault's line explains another fault's (borrowed_lines): an inner
# pit passes the load zone once per shaft turn (BPFI +- k x shaft), a ball pit once per cage turn
# (2xBSF +- k x FTF), and an outer race's ball-pass line carries the cage rate where the balls are
# unevenly spaced or loaded (BPFO +- k x FTF).  Measured (docs/detector_confusion.md): an ER-16K
# inner pit on the skidding tier at 1000 rpm put its BPFI - 1 x shaft line on 2xBSF (the balls 5 %
# slow), and a ball pit its 2xBSF + 2 x FTF on BPFI (0.15 % apart on the ER-16K at pure rolling).
SIDEBANDS = {"inner": ("shaft", (1, 2)), "ball": ("ftf", (1, 2, 3, 4)), "outer": ("ftf", (1, 2, 3, 4))}
# a found line this close (share of its frequency) to another fault's sideband is that sideband:
# over the confusion table's 192 records the coincidences lay within 0.18 % (the found lines'
# frequencies are interpolated to a small part of a bin), the nearest pair that was none 0.52 %
COINCIDENCE_REL = 0.0025


def borrowed_lines(lines: dict, threshold: float = DETECTION_THRESHOLD) -> dict:
    """The detected faults whose line is another detected fault's sideband: ``{fault: (other fault,
    k)}``, the line found (``found_hz``) within ``COINCIDENCE_REL`` of the other's found line + k x
    its ``SIDEBANDS`` rate (the shaft rate, FTF x (1 + BPFI / BPFO) by the lines' expected
    frequencies, Hz or orders; or FTF), and nearer to it than to its own expected frequency.  A
    line of one fault's family, not the other's: an inner pit's BPFI - 1 x shaft line is no ball
    fault, a ball pit's 2xBSF + 2 x FTF no inner race.

    Where two lines are each other's sideband (the ball's and the outer race's families share the
    cage-rate spacing), the higher one (prominence) is the carrier and keeps its line."""
    keys = {fault: key for fault, key in FAULT_LINES.items() if fault != "cage"}
    try:
        ftf = float(lines["ftf"].expected_hz)
        shaft = ftf * (1.0 + float(lines["bpfi"].expected_hz) / float(lines["bpfo"].expected_hz))
    except (KeyError, ZeroDivisionError):
        return {}
    rates = {"shaft": shaft, "ftf": ftf}
    detected = {fault for fault, key in keys.items()
                if lines[key].prominence >= threshold and np.isfinite(lines[key].found_hz)}
    by = {}                 # fault -> {other fault: k}
    for fault in detected:
        found, expected = lines[keys[fault]].found_hz, lines[keys[fault]].expected_hz
        for other in detected - {fault}:
            rate_name, ks = SIDEBANDS[other]
            rate, anchor = rates[rate_name], lines[keys[other]].found_hz
            if not (np.isfinite(rate) and rate > 0):
                continue
            for k in (s * k for k in ks for s in (-1, 1)):
                off = abs(found - (anchor + k * rate))
                # nearer the sideband than its own frequency: a ball pit and an inner pit together
                # on seed 004's 6205 (b6205_ball_inner), whose BPFI lies 0.15 % below 2xBSF + 2 x FTF,
                # found BPFI 0.06 % from its own place and 0.21 % from the sideband: the inner pit's
                if off <= COINCIDENCE_REL * abs(found) and off < abs(found - expected):
                    by.setdefault(fault, {})[other] = k
                    break
    for fault, others in list(by.items()):
        for other in list(others):
            if fault in by.get(other, {}):      # each the other's sideband: the higher is the carrier
                lower, higher = sorted((fault, other), key=lambda f: lines[keys[f]].prominence)
                by[higher].pop(lower, None)
    return {fault: min(others.items(), key=lambda item: abs(item[1]))
            for fault, others in by.items() if others}


def borrowed_text(fault: str, borrowed: dict) -> str:
    """In words, the line of ``fault`` as another fault's sideband (``borrowed_lines``' entry
    ``borrowed[fault]``), e.g. "2xBSF sits on BPFI - 1 x shaft rate, a sideband of the inner
    fault's line: counted for inner, not ball"; "" where it is its own."""
    if fault not in borrowed:
        return ""
    other, k = borrowed[fault]
    rate = "shaft rate" if SIDEBANDS[other][0] == "shaft" else "FTF"
    return (f"{LINE_LABELS[FAULT_LINES[fault]]} sits on {LINE_LABELS[FAULT_LINES[other]]} "
            f"{'+' if k > 0 else '-'} {abs(k)} x {rate}, "
            f"a sideband of the {other} fault's line: counted for {other}, not {fault}")


def no_defect_note(fault: str, bpfo_prominence: float = float("nan")) -> tuple | None:
    """What a fault verdict (``fault``: :func:`diagnose`'s ``verdict``) on a scene *without* a
    defect means, in words: ``(what the line is, what to do)``, or None where the verdict is
    healthy.  ``bpfo_prominence``: the height of the BPFO line over its local median, which the
    words of an "outer" verdict give.  A bearing with radial play rattles from ball to ball at
    the ball-pass frequency (varying compliance; seed 000 Fig. 9), and a detector that judges the
    height of the BPFO line alone calls that an outer-race fault."""
    if fault in ("healthy", "unknown"):
        return None
    if fault == "outer":
        return (f"this scene has no defect; the line at BPFO (x{bpfo_prominence:.0f}) is the "
                "ball-pass (varying compliance) line",
                "which the detector alone calls an outer-race fault: compare line heights with a healthy baseline")
    return ("this scene has no defect, so the line is not a defect's",
            "a false alarm of the detector: compare line heights with a healthy baseline")


def statistics(x: np.ndarray) -> dict:
    """RMS, kurtosis (3 for a Gaussian), crest factor, peak-to-peak of a waveform."""
    x = one_channel(x)
    x = x - x.mean()
    rms = float(np.sqrt(np.mean(x * x)))
    kurt = float(np.mean(x ** 4) / rms ** 4) if rms > 0 else float("nan")
    crest = float(np.max(np.abs(x)) / rms) if rms > 0 else float("nan")
    return {"rms": rms, "kurtosis": kurt, "crest_factor": crest, "peak_to_peak": float(np.ptp(x))}


def band_rms(x: np.ndarray, fs: float, edges=(0.0, 1000.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0)) -> list:
    """RMS (units of ``x``) in each frequency band [edges[i], edges[i+1]) Hz, from a Welch
    spectrum (Hann, 4096-sample segments); bands above Nyquist give 0.  Their squares add up to
    the mean square of the signal below the last edge."""
    from scipy.signal import welch

    x = one_channel(x)
    f, p = welch(x - x.mean(), fs, nperseg=min(4096, x.size))
    df = f[1] - f[0]
    return [float(np.sqrt(np.sum(p[(f >= lo) & (f < hi)]) * df)) for lo, hi in zip(edges[:-1], edges[1:])]

"""The accelerometer chain: from sensor-mount acceleration at the internal rate to output samples.

1. Sensor resonance (optional): the mounted accelerometer's own second-order response
   H(s) = w^2 / (s^2 + 2 zeta w s + w^2), flat below its resonance and peaking at it, applied
   by a biquad at the internal rate with the poles mapped exactly and the numerator fitted to
   H over the output band (``design_resonance``), when the resonance lies below 0.45 x the
   internal rate.  Above that no biquad at the internal rate can hold the resonance itself, but
   its lift over the output band is still there (4 % at 6 kHz for a 30 kHz sensor): a short
   non-causal FIR fitted to H over that band (``resonance_band_taps``) is folded into the
   anti-aliasing taps, its reach ahead added to the lookahead.
2. Anti-aliasing: a linear-phase Kaiser FIR, passband to 0.4 x the output rate, at least 60 dB
   down from the output Nyquist frequency on, as a real acquisition chain does: nothing above
   Nyquist folds back.  Its group delay (``lookahead`` internal samples) is compensated by the
   simulator running the physics that far ahead, so output sample k is the acquisition of time
   k / sample_rate exactly.
3. Decimation to the output rate (polyphase: only the kept samples are computed).
4. Noise: white, ``noise_density`` (m/s^2/sqrt(Hz)) over the output band, from a counter-based
   generator indexed by the absolute sample (chunk-invariant); one Box-Muller pair per sample
   gives both axes.
5. Clipping at +-``range`` (m/s^2), as the real sensor saturates.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .rng import uniform

AA_PASS = 0.4     # passband edge / output rate
AA_STOP = 0.5     # stopband edge / output rate (the output Nyquist frequency)
AA_ATTEN_DB = 60.0


@njit(cache=True)
def _biquad2(x, b, a, zi):
    """Direct form II transposed over the two columns of x (n, 2) in place; zi (2, 2) state.
    Both columns in one loop: their recursions are independent, so they overlap (a recursion is
    latency bound)."""
    b0, b1, b2, a1, a2 = b[0], b[1], b[2], a[1], a[2]
    p1, p2, q1, q2 = zi[0, 0], zi[1, 0], zi[0, 1], zi[1, 1]
    for i in range(x.shape[0]):
        u = x[i, 0]
        v = x[i, 1]
        y = b0 * u + p1
        z = b0 * v + q1
        p1 = b1 * u - a1 * y + p2
        q1 = b1 * v - a1 * z + q2
        p2 = b2 * u - a2 * y
        q2 = b2 * v - a2 * z
        x[i, 0] = y
        x[i, 1] = z
    zi[0, 0], zi[1, 0], zi[0, 1], zi[1, 1] = p1, p2, q1, q2


def _slp_njit(signature):
    """``njit(signature, cache=True)`` compiled with LLVM's SLP vectoriser on.  numba leaves it
    off by default (config.SLP_VECTORIZE, read when a function is compiled); here it packs the
    eight independent lanes of the FIR into vector instructions: measured 1.16 -> 0.78 ms per
    signal-second at 4x.  Lane-wise packing does not reorder any sum, so results are unchanged.
    Compiled eagerly (at import) so that the switch is on exactly for this compilation."""
    import numba.core.config as nb_config

    def wrap(fn):
        old = nb_config.SLP_VECTORIZE
        nb_config.SLP_VECTORIZE = 1
        try:
            return njit(signature, cache=True)(fn)
        finally:
            nb_config.SLP_VECTORIZE = old

    return wrap


@_slp_njit("void(float64[::1], float64[:, ::1], int64, int64, int64, float64[:, ::1])")
def _polyphase(flat, taps2, m, first, n_out, out):
    """out[i, c] = sum_t taps[t] * buf[first + i*m + t, c] for the two columns of a (n, 2)
    buffer given as ``flat`` (its row-major ravel) and ``taps2`` (each tap twice, zero-padded to
    a multiple of 8, as rows of 8).

    Eight independent partial sums over consecutive elements of ``flat`` (lanes alternate
    between the columns): the compiler packs them into vector registers without reordering any
    sum (a single running sum is limited by add latency; measured ~5x slower).  The samples are
    read as rows of eight with constant column indices (no negative-index wraparound checks per
    element: they block vectorising): with m a multiple of 4 (every chain the simulator builds)
    through one (rows, 8) view of the whole stretch, output i starting m / 4 rows after output
    i - 1, four outputs per pass over the taps (a lane's sum is a chain of dependent adds, bound
    by their latency; four outputs' chains overlap: 37.5 -> 23.5 ns per output at 153 taps,
    the same bits); else through a view per output, whose reference counting costs about a
    third more (53 against 80 ns per output sample at 153 taps, one output per pass)."""
    nblk = taps2.shape[0]
    if m % 4 == 0 and n_out > 0:
        step = m // 4
        rows = (n_out - 1) * step + nblk
        seg = flat[2 * first:2 * first + 8 * rows].reshape((rows, 8))
        # four outputs at a time: each lane's sum is a chain of dependent adds (latency bound),
        # and the four outputs' chains are independent, so they overlap; every sum keeps its order
        n4 = n_out - n_out % 4
        for i in range(0, n4, 4):
            ra = i * step
            rb = ra + step
            rc = rb + step
            rd = rc + step
            a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
            b0 = b1 = b2 = b3 = b4 = b5 = b6 = b7 = 0.0
            c0 = c1 = c2 = c3 = c4 = c5 = c6 = c7 = 0.0
            d0 = d1 = d2 = d3 = d4 = d5 = d6 = d7 = 0.0
            for k in range(nblk):
                t0, t1, t2, t3 = taps2[k, 0], taps2[k, 1], taps2[k, 2], taps2[k, 3]
                t4, t5, t6, t7 = taps2[k, 4], taps2[k, 5], taps2[k, 6], taps2[k, 7]
                a0 += t0 * seg[ra + k, 0]
                a1 += t1 * seg[ra + k, 1]
                a2 += t2 * seg[ra + k, 2]
                a3 += t3 * seg[ra + k, 3]
                a4 += t4 * seg[ra + k, 4]
                a5 += t5 * seg[ra + k, 5]
                a6 += t6 * seg[ra + k, 6]
                a7 += t7 * seg[ra + k, 7]
                b0 += t0 * seg[rb + k, 0]
                b1 += t1 * seg[rb + k, 1]
                b2 += t2 * seg[rb + k, 2]
                b3 += t3 * seg[rb + k, 3]
                b4 += t4 * seg[rb + k, 4]
                b5 += t5 * seg[rb + k, 5]
                b6 += t6 * seg[rb + k, 6]
                b7 += t7 * seg[rb + k, 7]
                c0 += t0 * seg[rc + k, 0]
                c1 += t1 * seg[rc + k, 1]
                c2 += t2 * seg[rc + k, 2]
                c3 += t3 * seg[rc + k, 3]
                c4 += t4 * seg[rc + k, 4]
                c5 += t5 * seg[rc + k, 5]
                c6 += t6 * seg[rc + k, 6]
                c7 += t7 * seg[rc + k, 7]
                d0 += t0 * seg[rd + k, 0]
                d1 += t1 * seg[rd + k, 1]
                d2 += t2 * seg[rd + k, 2]
                d3 += t3 * seg[rd + k, 3]
                d4 += t4 * seg[rd + k, 4]
                d5 += t5 * seg[rd + k, 5]
                d6 += t6 * seg[rd + k, 6]
                d7 += t7 * seg[rd + k, 7]
            out[i, 0] = (a0 + a2) + (a4 + a6)
            out[i, 1] = (a1 + a3) + (a5 + a7)
            out[i + 1, 0] = (b0 + b2) + (b4 + b6)
            out[i + 1, 1] = (b1 + b3) + (b5 + b7)
            out[i + 2, 0] = (c0 + c2) + (c4 + c6)
            out[i + 2, 1] = (c1 + c3) + (c5 + c7)
            out[i + 3, 0] = (d0 + d2) + (d4 + d6)
            out[i + 3, 1] = (d1 + d3) + (d5 + d7)
        for i in range(n4, n_out):
            r0 = i * step
            s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
            for k in range(nblk):
                s0 += taps2[k, 0] * seg[r0 + k, 0]
                s1 += taps2[k, 1] * seg[r0 + k, 1]
                s2 += taps2[k, 2] * seg[r0 + k, 2]
                s3 += taps2[k, 3] * seg[r0 + k, 3]
                s4 += taps2[k, 4] * seg[r0 + k, 4]
                s5 += taps2[k, 5] * seg[r0 + k, 5]
                s6 += taps2[k, 6] * seg[r0 + k, 6]
                s7 += taps2[k, 7] * seg[r0 + k, 7]
            out[i, 0] = (s0 + s2) + (s4 + s6)
            out[i, 1] = (s1 + s3) + (s5 + s7)
        return
    for i in range(n_out):
        seg = flat[2 * (first + i * m):2 * (first + i * m) + 8 * nblk].reshape((nblk, 8))
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
        for k in range(nblk):
            s0 += taps2[k, 0] * seg[k, 0]
            s1 += taps2[k, 1] * seg[k, 1]
            s2 += taps2[k, 2] * seg[k, 2]
            s3 += taps2[k, 3] * seg[k, 3]
            s4 += taps2[k, 4] * seg[k, 4]
            s5 += taps2[k, 5] * seg[k, 5]
            s6 += taps2[k, 6] * seg[k, 6]
            s7 += taps2[k, 7] * seg[k, 7]
        out[i, 0] = (s0 + s2) + (s4 + s6)
        out[i, 1] = (s1 + s3) + (s5 + s7)


@njit(cache=True)
def _noise_clip(out, index0, seed, sigma, limit):
    """Add white noise (sigma, m/s^2) and clip at +-limit.  One Box-Muller pair per sample gives
    the two axes' independent normals (one log, sqrt, cos and sin per sample, not two)."""
    n = out.shape[0]
    for i in range(n):
        x = out[i, 0]
        y = out[i, 1]
        if sigma > 0.0:
            u1 = uniform(seed, 20, index0 + i)
            u2 = uniform(seed, 21, index0 + i)
            r = sigma * math.sqrt(-2.0 * math.log(1.0 - u1))
            th = 2.0 * math.pi * u2
            x += r * math.cos(th)
            y += r * math.sin(th)
        out[i, 0] = min(max(x, -limit), limit)
        out[i, 1] = min(max(y, -limit), limit)


@njit(cache=True)
def _commit(buf, nvalid, n, bq_b, bq_a, bq_z, tail, taps2, m, first, out, index0, seed, sigma, limit):
    """``AccelerometerChain.commit`` in one compiled call (a batch of the node is ~150 output
    samples: the Python around a handful of small calls cost as much as the FIR).

    buf (rows, 2): rows [0, nvalid) held samples, the next n rows new ones; bq_*: the resonance
    biquad (b empty: none); first: buffer row of the first output's first tap; out (n_out, 2):
    n_out may be 0 (only feed).  Returns the number of rows held afterwards: the rows the next
    outputs' taps reach back to, moved to the front of the buffer."""
    if bq_b.shape[0] > 0:
        _biquad2(buf[nvalid:nvalid + n], bq_b, bq_a, bq_z)
    nvalid += n
    n_out = out.shape[0]
    if n_out == 0:
        return nvalid
    # zero rows after the samples: the FIR's zero-padded taps read up to ``tail`` rows past them
    buf[nvalid:nvalid + tail] = 0.0
    _polyphase(buf.ravel(), taps2, m, first, n_out, out)
    lo = first + n_out * m
    for r in range(nvalid - lo):
        buf[r, 0] = buf[lo + r, 0]
        buf[r, 1] = buf[lo + r, 1]
    _noise_clip(out, index0, seed, sigma, limit)
    return nvalid - lo


def design_antialias(oversample: int) -> np.ndarray:
    """Kaiser low-pass taps at the internal rate for decimation by ``oversample``; odd length
    2D+1 with D a multiple of ``oversample`` (so the delay is a whole number of output samples).

    ``scipy.signal.kaiserord`` and ``firwin(2D + 1, cutoff, window=("kaiser", beta))`` written out
    in their own arithmetic, bit for bit (``test_sensor.py`` compares them for every oversample
    from 1 to 128): importing ``scipy.signal`` took 0.4-1.7 s of every node's, render's and
    test process's start (scipy 1.17 parses the docstrings of its functions as it imports them),
    a third of a ``Simulator``'s construction with its kernels cached.  ``scipy.special`` is
    imported by ``scipy.optimize`` anyway, which the tiers' static balance takes."""
    from scipy.special import i0

    m = oversample
    width = (AA_STOP - AA_PASS) / m                # transition, as a fraction of the internal rate
    # kaiserord(AA_ATTEN_DB, 2 width): Kaiser's order formula (+1: taps) and, above 50 dB, his beta
    numtaps = int(math.ceil((AA_ATTEN_DB - 7.95) / 2.285 / (np.pi * (2.0 * width)) + 1))
    beta = 0.1102 * (AA_ATTEN_DB - 8.7)
    d = int(math.ceil((numtaps - 1) / 2 / m)) * m
    cutoff = 0.5 * (AA_PASS + AA_STOP) / m          # cycles per internal sample
    # firwin: the ideal low-pass's sinc (cutoff 2 * cutoff in units of the Nyquist frequency), the
    # symmetric Kaiser window, then unit gain at DC
    n = 2 * d + 1
    k = np.arange(0, n, dtype=float) - 0.5 * (n - 1)
    right = 2.0 * cutoff
    taps = right * np.sinc(right * k)
    half = (n - 1) / 2.0
    taps *= i0(beta * np.sqrt(1 - ((np.arange(0, n) - half) / half) ** 2.0)) / i0(beta)
    taps /= np.sum(taps)
    return taps


RESONANCE_TAPS_REACH = 3     # internal samples each side of the band-fitted resonance FIR


def resonance_band_taps(f_res: float, zeta: float, rate: float, band: float,
                        reach: int = RESONANCE_TAPS_REACH) -> np.ndarray:
    """FIR g[k], k = -reach .. reach (the sample k internal samples earlier: k < 0 reads ahead),
    whose response sum_k g[k] exp(-2 pi j f k / rate) is fitted by least squares to the sensor's
    H(s) = w^2 / (s^2 + 2 zeta w s + w^2) over 0 .. ``band`` Hz, for a resonance ``f_res`` (Hz)
    too close to or above the Nyquist frequency of ``rate`` for ``design_resonance``.  What the
    resonance does above the band, the anti-aliasing filter removes anyway.  At 60 kHz over
    7.5 kHz: within 3e-5 of H for 27 kHz to 1 MHz and damping ratios 0.02 to 0.7, where leaving
    the resonance out was 8 % off at 27 kHz and 0.03 % at 1 MHz."""
    w = 2.0 * math.pi * f_res
    f = np.linspace(0.0, band, 512)
    s = 2j * math.pi * f
    target = w * w / (s * s + 2.0 * zeta * w * s + w * w)
    basis = np.exp(-2j * math.pi * np.outer(f, np.arange(-reach, reach + 1)) / rate)
    g = np.linalg.lstsq(np.concatenate([basis.real, basis.imag]),
                        np.concatenate([target.real, target.imag]), rcond=None)[0]
    return np.asarray(g, float)


def design_resonance(f_res: float, zeta: float, rate: float, band: float):
    """Digital biquad (b, a) at ``rate`` Hz for the sensor's H(s) = w^2 / (s^2 + 2 zeta w s + w^2):
    poles mapped exactly (z = exp(s / rate), so the resonance sits where it is), numerator fitted
    by least squares to H over 0 .. ``band`` Hz (the output band that survives the anti-aliasing
    filter).  The bilinear transform pre-warped at the resonance, used before, compresses the
    frequency axis below it: 8.7 % error at 6.75 kHz for a 22 kHz sensor at 60 kHz; this gives
    1e-3 there and 1e-7 at 480 kHz."""
    w = 2.0 * math.pi * f_res
    poles = np.roots([1.0, 2.0 * zeta * w, w * w])
    a = np.real(np.poly(np.exp(poles / rate)))
    f = np.linspace(0.0, band, 256)
    s = 2j * math.pi * f
    target = w * w / (s * s + 2.0 * zeta * w * s + w * w)
    zinv = np.exp(-2j * math.pi * f / rate)
    basis = np.stack([np.ones_like(zinv), zinv, zinv * zinv], axis=1)
    rhs = target * (a[0] + a[1] * zinv + a[2] * zinv * zinv)
    b = np.linalg.lstsq(np.concatenate([basis.real, basis.imag]),
                        np.concatenate([rhs.real, rhs.imag]), rcond=None)[0]
    return np.asarray(b, float), np.asarray(a, float)


class AccelerometerChain:
    """Turns (n*m, 2) sensor-mount acceleration into (n, 2) output samples; keeps its state so
    that chunked processing equals one long call."""

    def __init__(self, sensor, sample_rate: float, oversample: int, seed: int):
        self.sensor = sensor
        self.sample_rate = float(sample_rate)
        self.m = int(oversample)
        self.seed = int(seed)
        self.axis_columns = [0 if a == "x" else 1 for a in sensor.axes]
        internal = self.sample_rate * self.m
        # 1. sensor resonance
        self._bq = None
        f = sensor.resonance_hz
        band = AA_STOP * self.sample_rate
        if 0.0 < f < 0.45 * internal:
            b, a = design_resonance(f, sensor.damping_ratio, internal, band)
            self._bq = (b, a, np.zeros((2, 2)))
        # for the compiled commit: an empty numerator means "no resonance"
        self._bq_b, self._bq_a, self._bq_z = self._bq or (np.zeros(0), np.zeros(3), np.zeros((2, 2)))
        # 2. anti-aliasing FIR
        if self.m > 1:
            self.taps = design_antialias(self.m)
            self.half = (self.taps.size - 1) // 2
        else:
            self.taps = np.ones(1)
            self.half = 0
        if f > 0.0 and self._bq is None:
            # the resonance's lift over the band, folded into the taps (until 2026-11-30 left out
            # without a word: a 30 kHz sensor at 15 kHz lost its 4 % at 6 kHz, 26 kHz kept 5.6 %).
            # The FIR sums taps[t] x[n - half + t], so g's k (x[n - k]) is t - half = -k: g
            # reversed.  Its reach is padded to whole output samples, so that the delay stays a
            # whole number of them (design_antialias's rule), which the lookahead, half / m, covers
            reach = -(-RESONANCE_TAPS_REACH // self.m) * self.m
            g = np.zeros(2 * reach + 1)
            g[reach - RESONANCE_TAPS_REACH:reach + RESONANCE_TAPS_REACH + 1] = resonance_band_taps(
                f, sensor.damping_ratio, internal, band)
            self.taps = np.convolve(self.taps, g[::-1])
            self.half += reach
        nt = self.taps.size
        self._taps2 = np.zeros(-(-2 * nt // 8) * 8)
        self._taps2[0:2 * nt:2] = self.taps
        self._taps2[1:2 * nt:2] = self.taps
        self._taps2 = self._taps2.reshape(-1, 8)
        self._tail = (self._taps2.size - 2 * nt + 1) // 2   # rows the zero-padded taps read past the data
        self.lookahead_samples = self.half // self.m
        # internal samples held for the FIR in one buffer that lives as long as the chain (rows
        # [0, _nvalid) hold samples, the first of them is absolute internal index _buf_start;
        # rows after them are where the next samples go, written there by the tier directly):
        # no allocation and no copy of the input per batch
        self._buf = np.zeros((self.half + self._tail + 4096, 2))   # x[-D .. -1] = 0: at rest before t = 0
        self._nvalid = self.half
        self._buf_start = -self.half
        self._next_internal = 0                  # absolute internal index of the next input
        self._sigma = sensor.noise_density * math.sqrt(0.5 * self.sample_rate)

    def input_view(self, n: int) -> np.ndarray:
        """A writable (n, 2) view of the buffer where the next n internal samples go (m/s^2 of
        the sensor mount; x, y); fill it, then call ``commit``.  Valid until the next call."""
        need = self._nvalid + n + self._tail
        if need > self._buf.shape[0]:
            buf = np.zeros((max(need, 2 * self._buf.shape[0]), 2))
            buf[:self._nvalid] = self._buf[:self._nvalid]
            self._buf = buf
        return self._buf[self._nvalid:self._nvalid + n]

    def commit(self, n: int, index0: int | None = None) -> np.ndarray | None:
        """Take the n samples written into ``input_view(n)`` (through the sensor resonance).
        ``index0`` None: only feed them (the lookahead); otherwise return the n / m output
        samples starting at output index ``index0`` (m/s^2, (n / m, 2), a new array)."""
        n_out = 0 if index0 is None else n // self.m
        out = np.empty((n_out, 2))
        first = 0 if index0 is None else index0 * self.m - self.half - self._buf_start
        self._nvalid = _commit(self._buf, self._nvalid, n, self._bq_b, self._bq_a, self._bq_z,
                               self._tail, self._taps2, self.m, first, out, 0 if index0 is None else index0,
                               self.seed, self._sigma, self.sensor.range)
        self._next_internal += n
        if index0 is None:
            return None
        self._buf_start = (index0 + n_out) * self.m - self.half
        return out

    def prime(self, acc_internal: np.ndarray):
        """Feed the lookahead (the first D internal samples) without producing output."""
        n = acc_internal.shape[0]
        self.input_view(n)[:] = acc_internal
        self.commit(n)

    def process(self, acc_internal: np.ndarray, index0: int) -> np.ndarray:
        """Feed n*m internal samples; return the n output samples starting at ``index0``."""
        n = acc_internal.shape[0]
        self.input_view(n)[:] = acc_internal
        return self.commit(n, index0)

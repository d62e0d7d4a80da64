"""Reading Case Western Reserve University (CWRU) bearing recordings (``.mat`` files).

Each file holds one test: ``X<nnn>_DE_time`` (drive-end accelerometer, g), usually
``X<nnn>_FE_time`` (fan end) and ``X<nnn>_BA_time`` (base), and ``X<nnn>RPM`` (shaft speed).
Nothing in the file says what the condition or the sample rate is: both come from the
published file names, e.g. ``12k_Drive_End_OR007@6_0_130.mat`` = 12 kHz, drive-end bearing,
outer race, 0.007 in, at 6 o'clock, 0 hp, test 130.  ``normal_<hp>_<nnn>.mat`` is the CWRU
"normal baseline"; the data center sampled those at 48 kHz (checked on ``normal_0_97``: read at
12 kHz its shaft lines fall on quarter orders 3.75, 4.25, 5.5, 5.75 x; read at 48 kHz they fall
on whole orders 15, 16, 18, 20, 22, 23 x and line up with the same machine lines, Hz for Hz,
in the 12 kHz fault recordings).  :func:`shaft_order_check` repeats that test on any file.

Units out: acceleration in m/s^2 (the files are in g), speeds in rpm and rad/s, rates in Hz.
A file that cannot be used raises :class:`~bearing_sim_ros.errors.UserError` with one line.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..catalog import G                       # m/s^2 per g
from ..errors import UserError, short_repr

NORMAL_BASELINE_RATE = 48000.0                # Hz: CWRU normal baseline files (see module doc)
# shaft speed of the CWRU rig by motor load (hp), when a file has no RPM variable (rpm)
NOMINAL_RPM = {0: 1797.0, 1: 1772.0, 2: 1750.0, 3: 1730.0}
CONDITIONS = ("normal", "inner", "outer", "ball")
_FAULT_CODES = {"IR": "inner", "OR": "outer", "B": "ball"}

_FAULT_NAME = re.compile(
    r"^(?P<rate>12|48)k_(?P<end>Drive|Fan)_End_(?P<code>IR|OR|B)(?P<size>\d{3})"
    r"(?:@(?P<clock>\d{1,2}))?_(?P<hp>\d)(?:_(?P<num>\d+))?$", re.IGNORECASE)
_NORMAL_NAME = re.compile(r"^normal_(?P<hp>\d)(?:_(?P<num>\d+))?$", re.IGNORECASE)


@dataclass(frozen=True)
class FileInfo:
    """What a CWRU file name says.  size_in: fault diameter (inch); clock: outer-race fault
    position (o'clock); load_hp: motor load; sample_rate: Hz; bearing_end: "drive" | "fan"."""

    condition: str
    size_in: float | None
    clock: int | None
    load_hp: int | None
    sample_rate: float
    bearing_end: str
    number: str | None
    rate_source: str

    @property
    def scene(self) -> str | None:
        """The shipped scene that models this test, by naming convention
        (cwru_6205_normal, cwru_6205_ir007, cwru_6205_or007_6, cwru_6205_b007, ...)."""
        if self.bearing_end != "drive":
            return None
        if self.condition == "normal":
            return "cwru_6205_normal"
        code = {"inner": "ir", "outer": "or", "ball": "b"}[self.condition]
        mils = f"{round(self.size_in * 1000):03d}"
        tail = f"_{self.clock}" if self.condition == "outer" and self.clock is not None else ""
        return f"cwru_6205_{code}{mils}{tail}"


def parse_name(path: str | Path) -> FileInfo | None:
    """Condition, fault size, position, load and sample rate from a CWRU file name, or None if
    the name does not follow the data center's convention."""
    stem = Path(path).stem
    m = _NORMAL_NAME.match(stem)
    if m:
        return FileInfo("normal", None, None, int(m["hp"]), NORMAL_BASELINE_RATE, "drive", m["num"],
                        "file name (normal baseline, 48 kHz)")
    m = _FAULT_NAME.match(stem)
    if m:
        return FileInfo(_FAULT_CODES[m["code"].upper()], int(m["size"]) / 1000.0,
                        int(m["clock"]) if m["clock"] else None, int(m["hp"]),
                        float(m["rate"]) * 1000.0, m["end"].lower(), m["num"],
                        f"file name ({m['rate']}k)")
    return None


@dataclass
class Recording:
    """One CWRU drive-end recording, ready to compare.

    accel: (n,) drive-end acceleration, m/s^2; sample_rate: Hz; rpm: shaft speed (rev/min);
    channel: the variable read; rpm_source: where the speed came from.
    """

    path: Path
    info: FileInfo
    accel: np.ndarray
    sample_rate: float
    rpm: float
    channel: str
    rpm_source: str
    notes: list = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.path.name

    @property
    def condition(self) -> str:
        return self.info.condition

    @property
    def scene(self) -> str | None:
        return self.info.scene

    @property
    def shaft_speed(self) -> float:
        """rad/s."""
        return self.rpm * 2.0 * math.pi / 60.0

    @property
    def shaft_hz(self) -> float:
        return self.rpm / 60.0

    @property
    def duration(self) -> float:
        return self.accel.size / self.sample_rate


def _load_mat(path: Path) -> dict:
    from scipy.io import loadmat

    try:
        return loadmat(str(path))
    except FileNotFoundError:
        raise UserError(f"--cwru {str(path)!r}: no such file") from None
    except Exception as exc:  # noqa: BLE001 - scipy raises many types for a bad file
        reason = str(exc).splitlines()[0] if str(exc) else exc.__class__.__name__
        raise UserError(f"--cwru {str(path)!r}: not a readable MATLAB .mat file ({reason}); "
                        f"expected a CWRU recording with X<nnn>_DE_time") from None


def _pick(data: dict, suffix: str, number: str | None) -> str | None:
    """The variable ending in ``suffix``, preferring the one whose test number matches the file
    name (a few CWRU files carry a second test's channels too)."""
    keys = sorted(k for k in data if not k.startswith("__") and k.endswith(suffix))
    if not keys:
        return None
    if number is not None:
        for k in keys:
            digits = re.match(r"X0*(\d+)", k)
            if digits and int(digits.group(1)) == int(number):
                return k
    return keys[0]


def _speed(value) -> float | None:
    """The first number of a .mat RPM variable where it is a finite speed > 0 (rpm), else None:
    ``float()`` of a text one was a traceback, of an infinite one a run at infinite speed."""
    try:
        first = np.ravel(np.asarray(value, dtype=float))[:1]
    except (TypeError, ValueError):
        return None
    return float(first[0]) if first.size and math.isfinite(first[0]) and first[0] > 0 else None


def read_recording(path: str | Path, sample_rate: float | None = None) -> Recording:
    """Read one CWRU ``.mat`` file: the drive-end channel in m/s^2, the speed from its RPM
    variable (nominal speed for the load when it has none), the condition and sample rate from
    the file name (``sample_rate`` overrides the rate, Hz)."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"--cwru {str(path)!r}: no such file")
    if path.suffix.lower() != ".mat":
        raise UserError(f"--cwru {str(path)!r}: not a .mat file; expected a CWRU recording "
                        f"(<name>.mat with X<nnn>_DE_time) or a folder of them")
    info = parse_name(path)
    data = _load_mat(path)
    number = info.number if info else None
    de = _pick(data, "_DE_time", number)
    if de is None:
        names = ", ".join(k for k in data if not k.startswith("__")) or "none"
        raise UserError(f"--cwru {str(path)!r}: no drive-end channel X<nnn>_DE_time "
                        f"(variables: {names})")
    try:
        x = np.asarray(data[de], dtype=float).ravel()
    except (TypeError, ValueError):
        # text or a struct where the samples go (another tool's file): numpy's "could not convert
        # string to float" was a traceback and "internal error"
        raise UserError(f"--cwru {str(path)!r}: {de} = {short_repr(data[de])} is not numbers; expected the "
                        f"drive-end accelerometer's samples (g)") from None
    if x.size < 1000 or not np.all(np.isfinite(x)):
        raise UserError(f"--cwru {str(path)!r}: {de} has {x.size} samples or non-finite values; "
                        f"expected a finite recording of at least 1000 samples")
    notes = []
    if info is None:
        raise UserError(f"--cwru {str(path)!r}: file name does not say the condition; expected "
                        f"a CWRU name like normal_0_97.mat or 12k_Drive_End_IR007_0_105.mat")
    rpm_key = _pick(data, "RPM", number)
    rpm = _speed(data[rpm_key]) if rpm_key is not None else None
    if rpm is not None:
        rpm_source = rpm_key
    elif rpm_key is not None:
        # text, NaN, 0 or a negative number: not a speed to run the simulation at
        rpm = NOMINAL_RPM.get(info.load_hp, 1797.0)
        rpm_source = f"nominal for {info.load_hp} hp ({rpm_key} = {short_repr(data[rpm_key])} is not a speed)"
        notes.append(f"{rpm_key} = {short_repr(data[rpm_key])} is not a speed: nominal {rpm:g} rpm for "
                     f"{info.load_hp} hp used")
    else:
        rpm = NOMINAL_RPM.get(info.load_hp, 1797.0)
        rpm_source = f"nominal for {info.load_hp} hp (no RPM variable)"
        notes.append(f"no RPM variable: nominal {rpm:g} rpm for {info.load_hp} hp used")
    fs = float(sample_rate) if sample_rate else info.sample_rate
    rec = Recording(path, info, x * G, fs, rpm, de, rpm_source, notes)
    check = shaft_order_check(rec.accel, fs, rpm)
    if check["best_rate"] != fs:
        notes.append(f"shaft-order check prefers {check['best_rate']:g} Hz over {fs:g} Hz "
                     f"({check['scores']})")
    return rec


def find_recordings(folder: str | Path) -> list:
    """The ``.mat`` files in ``folder`` (sorted by name), or the one file given."""
    if not str(folder).strip():       # Path("") is the current folder
        raise UserError(f"--cwru {str(folder)!r}: an empty path; give a folder of CWRU .mat files")
    folder = Path(folder)
    if folder.is_file():
        return [folder]
    if not folder.is_dir():
        raise UserError(f"--cwru {str(folder)!r}: no such folder; give a folder of CWRU .mat files")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".mat" and p.is_file())
    if not files:
        raise UserError(f"--cwru {str(folder)!r}: no .mat files in it; expected CWRU recordings")
    return files


def shaft_order_check(x: np.ndarray, fs: float, rpm: float, candidates=(12000.0, 48000.0),
                      lines: int = 30, tol: float = 0.03) -> dict:
    """Which sample rate makes the strongest spectral lines of ``x`` whole orders of the shaft?

    A rotating machine's vibration below 1 kHz is dominated by shaft harmonics; read at the
    wrong rate, they land on fractional orders.  For each candidate rate (Hz) count how many of
    the ``lines`` strongest peaks (between 0.5 x and 35 x shaft speed) lie within ``tol`` order
    of a whole order.  Returns ``{"best_rate", "scores": {rate: fraction}}``.
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(n)))
    fr = rpm / 60.0
    scores = {}
    for rate in candidates:
        freqs = np.fft.rfftfreq(n, 1.0 / rate)
        sel = np.flatnonzero((freqs > 0.5 * fr) & (freqs < 35.0 * fr))
        if sel.size < lines:
            scores[rate] = 0.0
            continue
        order = sel[np.argsort(spec[sel])[::-1]]
        picked = []
        min_gap = 0.2 * fr                         # one peak per line, not its skirt
        for i in order:
            if all(abs(freqs[i] - freqs[j]) > min_gap for j in picked):
                picked.append(i)
                if len(picked) == lines:
                    break
        orders = freqs[picked] / fr
        scores[rate] = float(np.mean(np.abs(orders - np.round(orders)) <= tol))
    best = max(scores, key=scores.get)
    return {"best_rate": float(best), "scores": {f"{k:g}": round(v, 2) for k, v in scores.items()}}

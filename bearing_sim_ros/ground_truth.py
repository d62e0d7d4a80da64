"""The ground truth in ``/diagnostics``: which faults the published signal holds, written and read
in one place.

A simulator knows what a real machine does not: which defects are in the signal and since when.
The node and ``bearing-sim render`` put that into every ``/diagnostics`` message (1 Hz), as the
last published sample has it (the message's stamp is the end of the published signal), in the
status named by :func:`status_name` (every rig publishes on the one ``/diagnostics``):

- ``faults_present``: the kinds of the defects there, in scene order: ``none``, ``outer``,
  ``inner, ball``;
- ``defect_sizes``: each scene defect's size in scene order, 0 before its onset to 1 at full size
  (``none`` for a scene without defects);
- ``fault_onsets_s``: for each kind present, the signal time (s after the first sample) of the
  first sample that held it: ``outer=5.000000``, ``ball=2.000000, outer=5.000000``; ``none``.
  With it an onset is known to the sample, not only to the 1 s between two messages;
- ``simulated_s``: the signal time of the message's stamp (s), which ties the two time lines
  together: an onset's stamp is ``stamp - (simulated_s - onset_s)``.

Defects only appear and grow, never vanish, so the faults present at any time up to a message's
stamp follow from its ``fault_onsets_s``: exactly those with an onset before that time.  (A
recording played with ``--loop`` starts over at each seam, stamps moved on; each message's onsets
are relative to its own stamp, so the truth between messages stays right, and
:func:`appearances` gives each pass's appearance.)

:func:`parse` reads one message's values into a :class:`Truth` on the consumer's own time line
(ns of stamps for a live subscriber, s of signal for a recording's report); :func:`faults_at`,
:func:`appearances` and :func:`first_detection` answer what a scorer asks.  A recording made
before ``fault_onsets_s`` existed still works: then a change is known only between two messages,
and :func:`appearances` says so with its bracket.
"""
from __future__ import annotations

from bisect import bisect_left, bisect_right
from typing import NamedTuple

FAULTS_KEY = "faults_present"
SIZES_KEY = "defect_sizes"
ONSETS_KEY = "fault_onsets_s"
TIME_KEY = "simulated_s"
SCENE_KEY = "scene"         # the scene the simulator runs (its YAML's name:, else the file name without .yaml)
BEARING_KEY = "bearing"     # that scene's bearing (``Bearing.name``): what the fault frequencies follow from
STATUS_SUFFIX = ": simulator"


def status_name(node: str) -> str:
    """The name of the simulator's status in ``/diagnostics``: ``<node>: simulator``, ``node`` the
    publishing node's full name without its leading slash (``bearing_sim``, ``rig1/bearing_sim``).
    Simulators in several namespaces all publish on the one ``/diagnostics``: this tells them apart."""
    return f"{node.strip('/')}{STATUS_SUFFIX}"


# ---- writing (the simulator's side) --------------------------------------------------------------
def diagnostics_values(kinds, sizes, onsets_s) -> dict:
    """The ground-truth keys for defects of ``kinds`` (scene order) at ``sizes`` (0-1 each) whose
    first samples came at ``onsets_s`` (signal s each): ``faults_present``, ``defect_sizes`` and
    ``fault_onsets_s``, as text.  A kind is present when any of its defects has a size above 0;
    its onset is the earliest of those defects'."""
    onset_of = {}
    for kind, size, onset in zip(kinds, sizes, onsets_s):
        if size > 0.0:
            onset_of[kind] = min(onset, onset_of.get(kind, onset))
    return {FAULTS_KEY: ", ".join(onset_of) or "none",
            SIZES_KEY: " ".join(f"{s:.4g}" for s in sizes) if len(sizes) else "none",
            ONSETS_KEY: ", ".join(f"{k}={t:.6f}" for k, t in onset_of.items()) or "none"}


# ---- reading (a consumer's side) -----------------------------------------------------------------
class Truth(NamedTuple):
    """One ``/diagnostics`` message's ground truth on a consumer's time line."""

    t: float            # the message's stamp, in the consumer's unit (ns, or s of signal)
    faults: tuple       # the kinds present, sorted: () for none
    sizes: tuple        # each scene defect's size 0-1, scene order: () for a scene without any
    onsets: dict | None  # kind -> when it appeared (same unit as t); None from before the key


def parse(values: dict, t, per_second: float = 1.0):
    """A :class:`Truth` from one message's key/value texts ``values``, stamped ``t`` in a unit of
    which ``per_second`` make a second (1e9 for ns; an int ``t`` gives whole-unit onsets).  None when
    the message carries no ground truth (another node's status, a recording from before the keys)
    or an unreadable one."""
    text = values.get(FAULTS_KEY)
    if text is None:
        return None
    faults = tuple(sorted({k.strip() for k in text.split(",")} - {"", "none"}))
    try:
        sizes_text = values.get(SIZES_KEY, "none")
        sizes = () if sizes_text == "none" else tuple(float(v) for v in sizes_text.split())
        onsets = None
        if ONSETS_KEY in values and TIME_KEY in values:
            now = float(values[TIME_KEY])
            onsets = {}
            for item in values[ONSETS_KEY].split(","):
                if item.strip() and item.strip() != "none":
                    kind, _, onset = item.partition("=")
                    since = (now - float(onset)) * per_second
                    onsets[kind.strip()] = t - (round(since) if isinstance(t, int) else since)
    except ValueError:
        return None
    return Truth(t, faults, sizes, onsets)


def faults_at(truths, t, slack=0):
    """The faults (sorted tuple of kinds) in the signal just before time ``t`` (e.g. a window's
    end: its last sample), by ``truths`` (:class:`Truth` in stamp order), or None when unknown.
    ``slack``: times this close count as equal (stamps rounded to the ns).

    Exact wherever a message stamped at or after ``t`` gives the onsets: the kinds that appeared
    before ``t``.  Otherwise (a recording without ``fault_onsets_s``, or ``t`` past the last
    message) the latest message at or before ``t``; before the first message, none if that one has
    none (defects do not vanish), else unknown.  A bisection on the stamps: a monitor that runs
    for hours asks this of thousands of messages at every verdict."""
    first = bisect_left(truths, t - slack, key=_stamp)
    later = next((truths[k] for k in range(first, len(truths)) if truths[k].onsets is not None), None)
    if later is not None:
        return tuple(sorted(k for k, onset in later.onsets.items() if onset < t - slack))
    before = _latest_at_or_before(truths, t, slack)
    if before is not None:
        return before.faults
    return () if truths and not truths[0].faults else None


def truth_before(truths, t, slack=0):
    """The latest :class:`Truth` stamped at or before ``t``, else the first; None without any (for
    what only the messages give, such as the defect sizes)."""
    before = _latest_at_or_before(truths, t, slack)
    return before if before is not None else (truths[0] if truths else None)


def forget_before(truths: list, t, slack=0) -> None:
    """Drop from the list ``truths`` (in stamp order) the messages that :func:`faults_at` asked
    at any time after ``t`` (by more than 2 ``slack``) no longer reads: those before the latest
    stamped at or before ``t``.  A consumer that asks at times that only move on (its windows'
    ends) keeps a few messages instead of one a second for as long as it runs."""
    k = bisect_right(truths, t + slack, key=_stamp)
    del truths[:max(0, k - 1)]


def _stamp(truth) -> float:
    return truth.t


def _latest_at_or_before(truths, t, slack):
    k = bisect_right(truths, t + slack, key=_stamp)
    return truths[k - 1] if k else None


class Appearance(NamedTuple):
    """A fault kind that appeared after the signal's start ``t0``: between ``earliest`` and
    ``latest`` (equal where ``fault_onsets_s`` gives the onset to the sample)."""

    kind: str
    earliest: float
    latest: float

    @property
    def exact(self) -> bool:
        return self.earliest == self.latest


def appearances(truths, t0, slack=0) -> list:
    """The fault kinds that appeared after ``t0`` (the first sample a consumer has), in order of
    appearance: :class:`Appearance` each, by the messages ``truths`` in order
    (:class:`AppearanceLog`, which a consumer that runs for hours keeps instead of the messages)."""
    log = AppearanceLog(slack)
    for truth in truths:
        log.add(truth)
    return log.appearances(t0)


class AppearanceLog:
    """What :func:`appearances` needs of the messages, kept as they come (``add``): a few entries
    per fault kind and appearance, not every 1 Hz message, so that a monitor left running does
    not grow with the run.

    From the onsets of the last message of each run of messages that has the kind; without
    onsets, from where a message first shows a kind that the one before it did not (the bracket
    between the two stamps).  Defects do not vanish, so a kind that leaves the messages means the
    signal started over (a recording played with ``--loop``, each pass's stamps moved on): its
    next appearance counts again.  A kind that stays while its onset moves past a message that
    already had it was there on both sides of such a seam (from the recording's first sample): no
    new appearance; its first stays (a move to the stamp of that message itself too: a recording's
    last message, its end status, is stamped at its very end, where the next pass starts).  Within
    one time line the onsets the messages give agree to their rounding (1 us of ``simulated_s``),
    far less than the time between two messages.
    ``slack``: times this close count as equal."""

    def __init__(self, slack=0):
        self.slack = slack
        self._ended = []            # (kind, onset) whose time line ended (the kind left the messages)
        # kind -> [its onset, the stamp of the last message with it, still on the onset's time line]
        self._current: dict = {}
        self._with_onsets = False   # any message had onsets: those alone count
        self._previous = None       # the last message, for the brackets of messages without onsets
        self._bracketed = []        # Appearance between two messages without onsets

    def add(self, truth: Truth) -> None:
        """Take one message's :class:`Truth` (in stamp order)."""
        if truth.onsets is not None:
            self._with_onsets = True
            for kind in [k for k in self._current if k not in truth.onsets]:
                self._ended.append((kind, self._current.pop(kind)[0]))   # gone: its time line ended
            for kind, on in truth.onsets.items():
                have = self._current.get(kind)
                if have is None:
                    self._current[kind] = [on, truth.t, True]
                    continue
                # a message shows a kind only once its onset is past (at least a sample before the
                # message's stamp, the end of the signal then), so an onset at or after the stamp of
                # the last message with it is another time line: a seam with the fault on both
                # sides, not new.  At the stamp itself is the usual seam: a recording's last
                # /diagnostics is its end status, at its very end, where the next pass begins.
                # 2 slack: an onset carries the rounding of two 1 us numbers (simulated_s and its
                # own); a sample (5 us at 200 kHz) is more
                if on >= have[1] - 2 * self.slack:
                    have[2] = False
                elif have[2]:
                    have[0] = on                # the latest message's, as it was
                have[1] = truth.t
        if self._previous is not None:
            for kind in sorted(set(truth.faults) - set(self._previous.faults)):
                self._bracketed.append(Appearance(kind, self._previous.t, truth.t))
        self._previous = truth

    def appearances(self, t0) -> list:
        """The kinds that appeared after ``t0``, in order of appearance (:func:`appearances`)."""
        if self._with_onsets:
            found = self._ended + [(kind, have[0]) for kind, have in self._current.items()]
            found = [Appearance(kind, on, on) for kind, on in found if on > t0 + self.slack]
        else:
            found = list(self._bracketed)
        return sorted(found, key=lambda a: (a.latest, a.kind))


def first_detection(scored, appearance: Appearance, slack=0):
    """The end of the first window of ``scored`` ((window end, verdict) in order) that calls
    ``appearance``'s kind once it is in the window (after ``latest``, the earliest it is certainly
    there), or None; and how many windows end after ``latest``."""
    since = [(end, v) for end, v in scored
             if (end > appearance.latest + slack if appearance.exact else end >= appearance.latest - slack)]
    found = next((end for end, v in since if v == appearance.kind), None)
    return found, len(since)

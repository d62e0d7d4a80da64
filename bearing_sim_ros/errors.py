"""Errors that reach the user as one line (exit status 2), never as a traceback."""
import reprlib


class _ShortRepr(reprlib.Repr):
    """``reprlib.Repr`` that keeps a numpy array on one line."""

    def repr_ndarray(self, x, level):
        """A numpy array on one line: numpy's repr puts each row of a 2-D one on a line of its
        own, and an error is one line (numpy itself cuts an array above 1000 entries)."""
        text = " ".join(line.strip() for line in repr(x).splitlines())
        if len(text) > self.maxother:          # as reprlib cuts any other object
            i = max(0, (self.maxother - 3) // 2)
            j = max(0, self.maxother - 3 - i)
            text = text[:i] + "..." + text[len(text) - j:]
        return text


_SHORT = _ShortRepr()
_SHORT.maxlevel = 3
_SHORT.maxlist = _SHORT.maxtuple = 8
_SHORT.maxdict = _SHORT.maxset = _SHORT.maxfrozenset = 6
_SHORT.maxstring = _SHORT.maxother = 80
_SHORT.maxlong = 40


def short_repr(value) -> str:
    """``repr(value)`` for an error message, shortened: a long list, mapping or string is cut with
    ``...`` (a 20 000-entry ``radial_load`` made a 100 kB "one line"); a short one is unchanged."""
    return _SHORT.repr(value)


class UserError(Exception):
    """A mistake on the user's side: a bad argument, scene or file.

    The message is one line that names what is wrong (key or argument), the value given and
    what is allowed.  The command line prints it and exits with status 2.
    """


class SceneError(UserError):
    """A scene file that cannot be used: unknown key, wrong type, value out of range."""


class SettingNames:
    """How a caller names its settings in the advice of a one-line error: the Python API's
    keyword arguments (``solver='reference'``), the command line's options (``--solver
    reference``), the node's parameters (``-p fidelity:=kinematic``).  ``keys``: the settings the
    caller has (the node has no ``solver``), so that the advice offers only what can be given."""

    def __init__(self, name, assign, keys: tuple):
        self.name = name            # key -> the caller's name for it
        self.assign = assign        # (key, value) -> how the caller sets it
        self.keys = tuple(keys)


SIMULATOR_SETTINGS = ("solver", "rk4_step", "oversample", "fidelity")
API_SETTINGS = SettingNames(lambda key: key, lambda key, value: f"{key}={value!r}", SIMULATOR_SETTINGS)
CLI_SETTINGS = SettingNames(lambda key: "--" + key.replace("_", "-"),
                            lambda key, value: f"--{key.replace('_', '-')} {value}", SIMULATOR_SETTINGS)
NODE_SETTINGS = SettingNames(lambda key: key, lambda key, value: f"-p {key}:={value}", ("oversample", "fidelity"))

"""Errors that reach the user as one line (exit status 2), never as a traceback."""


class UserError(Exception):
    """A mistake on the user's side: a bad argument, scene or file.

    The message is one line that names what is wrong (key or argument), the value given and
    what is allowed.  The command line prints it and exits with status 2.
    """


class SceneError(UserError):
    """A scene file that cannot be used: unknown key, wrong type, value out of range."""

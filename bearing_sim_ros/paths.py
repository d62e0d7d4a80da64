"""Where the shipped configuration lives: the source tree, or share/ of an installed package."""
from __future__ import annotations

import contextlib
import errno
import os
import stat
import sys
import tempfile
from pathlib import Path

PACKAGE = "bearing_sim_ros"
MCAP_MAGIC = b"\x89MCAP0\r\n"      # the first bytes of every MCAP file


def _installed_prefix():
    """``<prefix>`` of an installed package, ``<prefix>/lib/pythonX.Y/site-packages/
    bearing_sim_ros/`` (``dist-packages`` on Debian): a venv, ``~/.local`` of ``pip install
    --user``, a colcon ``install/bearing_sim_ros``, whose ``share/`` holds its data files.  None
    in a source checkout."""
    package = Path(__file__).resolve().parent
    if package.parent.name in ("site-packages", "dist-packages") and len(package.parents) > 3:
        return package.parents[3]
    return None


def config_dir() -> Path:
    """The ``config/`` folder: beside the package in a source checkout (pip -e, tests), else the
    ament share directory of an installed package (colcon, pip wheel): the one of the prefix the
    package is installed in, then sys.prefix's (``pip install --user`` is not there), then each
    of AMENT_PREFIX_PATH."""
    here = Path(__file__).resolve().parent.parent / "config"
    if (here / "bearings.yaml").is_file():
        return here
    prefix = _installed_prefix()
    candidates = [prefix / "share" / PACKAGE / "config"] if prefix else []
    candidates.append(Path(sys.prefix) / "share" / PACKAGE / "config")
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            candidates.append(Path(prefix) / "share" / PACKAGE / "config")
    for cand in candidates:
        if (cand / "bearings.yaml").is_file():
            return cand
    raise FileNotFoundError(f"cannot find the {PACKAGE} config folder (looked in "
                            f"{', '.join(str(c) for c in [here, *candidates])})")


def scenes_dir() -> Path:
    return config_dir() / "scenes"


def output_folder(text, option: str = "--out") -> Path:
    """The folder ``text`` (the value of ``option``) for a command's files, created if missing;
    a one-line UserError naming the option when it is empty, a file, cannot be created or cannot
    be written in (a file is made and removed there: ``report --out /proc/self`` found out after
    all its work, and bench after minutes)."""
    from .errors import UserError

    where = f"{option} = {str(text)!r}"
    if not str(text).strip():
        raise UserError(f"{where}: expected the path of a folder")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise UserError(f"{where}: exists and is not a folder; give a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"{where}: cannot create the folder ({exc.strerror})") from None
    try:
        _probe(out)
    except OSError as exc:
        raise UserError(f"{where}: cannot write in the folder ({exc.strerror})") from None
    return out


def _probe(folder: Path) -> None:
    """Make a file in ``folder`` and remove it: whether a file can be written there (OSError)."""
    fd, probe = tempfile.mkstemp(dir=folder, prefix=".bearing-sim-probe-")
    os.close(fd)
    os.unlink(probe)


def replaceable_file(path, where: str) -> Path:
    """The file ``path`` that a command replaces at the end of its work (``replace_file``),
    checked before the work: a one-line UserError (``where``: what writes it,
    ``--calibrate-fidelity``) when a folder is there or its folder cannot take a new file (one is
    made and removed there).  A symbolic link is followed: the file it points to is the one
    replaced, and is returned."""
    from .errors import UserError

    target = Path(path).resolve()
    if target.is_dir():
        raise UserError(f"{where}: cannot write {str(target)!r} (a folder is there)")
    try:
        _probe(target.parent)
    except OSError as exc:
        raise UserError(f"{where}: cannot write {str(target)!r} ({exc.strerror})") from None
    return target


def replace_file(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (``replacing``)."""
    with replacing(path, "w", encoding="utf-8") as f:
        f.write(text)


@contextlib.contextmanager
def replacing(path, mode: str = "wb", encoding: str | None = None):
    """A file object (``mode``, ``encoding``) whose content replaces ``path`` at the end of the
    block: written into a temporary file beside it, synced, then moved onto it, so that ``path``
    holds the old content or the new, never part of one (a full disk: a report's plot cut
    short, 118 784 bytes of a PNG, stayed beside the complete ones), and the temporary file goes
    when the block or the write fails.  A symbolic link is followed; the file keeps its
    permissions (a new one gets the umask's)."""
    path = Path(path).resolve()
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial")
    try:
        with os.fdopen(fd, mode, encoding=encoding) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        try:
            mode_bits = stat.S_IMODE(path.stat().st_mode)
        except FileNotFoundError:
            umask = os.umask(0)
            os.umask(umask)
            mode_bits = 0o666 & ~umask
        os.chmod(tmp, mode_bits)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def save_figure(fig, path, dpi: int) -> None:
    """The matplotlib figure ``fig`` as a PNG at ``path`` (``dpi`` dots per inch), whole or not at
    all (``replacing``)."""
    with replacing(path) as f:
        fig.savefig(f, format="png", dpi=dpi)


@contextlib.contextmanager
def writing_into(folder, option: str = "--out"):
    """Around a command's writes into ``folder`` (``output_folder``): an OSError (full disk,
    the folder gone or made read-only meanwhile) becomes a one-line UserError naming the option,
    the file and why, not a traceback."""
    from .errors import UserError

    try:
        yield
    except OSError as exc:
        name = f" {exc.filename}" if exc.filename else ""
        raise UserError(f"{option} = {str(folder)!r}: cannot write{name} "
                        f"({exc.strerror or exc.__class__.__name__})") from None


def input_file(text, where: str, expected: str, error=None) -> Path:
    """The existing regular file ``text`` to read; else a one-line ``error`` (a UserError class,
    default UserError) ``{where}: <what it is>; {expected}``: missing, a folder, not a regular
    file (a device, a pipe) or not to be looked at.  A folder used to be called "no such file",
    which sends the user looking for a typo in a path that exists."""
    from .errors import UserError

    if not str(text).strip():
        # Path("") is the current folder: an empty argument (an unset $VAR) was "is a folder"
        raise (error or UserError)(f"{where or repr(str(text))}: an empty path; {expected}")
    path = Path(text)
    try:
        mode = path.stat().st_mode
    except (FileNotFoundError, NotADirectoryError):
        problem = "no such file"
    except OSError as exc:
        problem = f"cannot read it ({exc.strerror or exc.__class__.__name__})"
    except ValueError:
        # a NUL in a path given in Python (the command line's cannot hold one): os.stat's
        # "embedded null byte" was a traceback
        problem = "not a path: it holds a NUL character"
    else:
        if stat.S_ISREG(mode):
            return path
        problem = "is a folder, not a file" if stat.S_ISDIR(mode) else \
            "is not a regular file (a device, pipe or socket)"
    raise (error or UserError)(f"{where}: {problem}; {expected}")


def output_file(text, option: str = "--out", keep=(), check: bool = True) -> Path:
    """The path ``text`` (the value of ``option``) of an .mcap file to write; a one-line
    UserError naming the option when it is empty or a folder (``open`` said
    "IsADirectoryError: '.'" for an empty one), or, with ``check``, when writing it would destroy
    what is not a recording (``check_replaceable``; ``keep``: the scene's own file).  Whether it
    can be written is the writer's to say."""
    from .errors import UserError

    where = f"{option} = {str(text)!r}"
    if not str(text).strip():
        raise UserError(f"{where}: expected the path of an .mcap file")
    out = Path(text)
    try:
        os.stat(out)
    except OSError as exc:
        # a link that leads back to itself was pathlib's "RuntimeError: Symlink loop" as an
        # internal error; a missing file (or a dangling link, whose target is written) is fine
        if exc.errno == errno.ELOOP:
            raise UserError(f"{where}: a symbolic link that loops (it leads back to itself); give another "
                            "path or remove the link") from None
    if out.is_dir():
        raise UserError(f"{where}: is a folder; expected the path of an .mcap file")
    if check:
        check_replaceable(out, where, keep)
    return out


def check_replaceable(path: Path, where: str, keep=()) -> None:
    """A one-line UserError (``where``: ``--out = 'x.mcap'``) when writing a recording to
    ``path`` would destroy a file that is not one: a path in ``keep`` (the scene's own file:
    ``render my.yaml --out my.yaml`` made the scene an MCAP), or an existing regular file that
    is neither empty nor an MCAP file (``MCAP_MAGIC``).  An MCAP file may be replaced (rendering
    to the same path again is normal use); a device or a pipe (/dev/null) is written to."""
    from .errors import UserError

    path = Path(path)
    for kept in keep:
        if kept and (Path(kept).resolve() == path.resolve()
                     or (path.exists() and Path(kept).exists() and os.path.samefile(kept, path))):
            raise UserError(f"{where}: is the scene's own file; give another path for the recording")
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode) or info.st_size == 0:
            return
        with open(path, "rb") as f:
            head = f.read(len(MCAP_MAGIC))
    except OSError:
        return              # missing, or not readable: the writer says whether it can write there
    if head != MCAP_MAGIC:
        raise UserError(f"{where}: exists and is not an MCAP recording, so it is not replaced; "
                        "give another path or remove the file first")

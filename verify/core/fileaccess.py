"""The one rule for every file verify reads or writes (docs/guide/untrusted.md).

The files of a project are untrusted: the model named on the command line, what it imports, the
``pyproject.toml`` above it, the files ``verify import`` reads, what lies in the way of generated code,
and the parser's cache. Each is read only when

- it lies inside an ``Area`` — the directories the run may read there — both as written (a ``..`` that
  climbs out is refused) and once symbolic links are followed (a link that leads out is refused);
- it is a regular file: a FIFO, a device or a socket could block or never end, so the file is opened
  non-blocking and checked on the open descriptor; with ``follow_links=False`` a symbolic link is
  refused too (``O_NOFOLLOW``).

A refused file is reported by its name only (``Refused``); what it holds is never read. Generated files
are written only below their output directory and never through a symbolic link (``links_below``,
``write_output``).
"""
from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field

#: why a file is refused: ``outside`` an area, a ``link`` where none is followed, ``special`` (a FIFO,
#: device or socket), a ``directory``, ``missing``, or a ``name`` no file can have (a NUL character)
REASONS = ("outside", "link", "special", "directory", "missing", "name")


def inside(path: str, directory: str) -> bool:
    """``path`` is ``directory`` or lies below it (both absolute and normalised)."""
    return path == directory or path.startswith(directory.rstrip(os.sep) + os.sep)


@dataclass(frozen=True)
class Area:
    """Directories a run may read files in: each as written and once symbolic links are followed."""

    directories: tuple[str, ...]
    absolute: tuple[str, ...] = field(init=False, repr=False, compare=False)
    real: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "absolute", tuple(os.path.abspath(d) for d in self.directories))
        object.__setattr__(self, "real", tuple(os.path.realpath(d) for d in self.directories))

    def holds_as_written(self, path: str) -> bool:
        """``path`` lies inside one of the directories, links not followed."""
        absolute = os.path.abspath(path)
        return any(inside(absolute, d) for d in self.absolute)

    def holds(self, path: str) -> bool:
        """``path`` lies inside one of the directories as written and once links are followed."""
        if "\0" in path or not self.holds_as_written(path):
            return False
        real = os.path.realpath(path)
        return any(inside(real, d) for d in self.real)


def area_of(paths: Sequence[str]) -> Area:
    """The area that paths named on the command line open: each directory, and the directory of each file."""
    return Area(tuple(p if os.path.isdir(p) else (os.path.dirname(p) or os.curdir) for p in paths))


class Refused(Exception):
    """A file the rule does not let be opened, and why (one of ``REASONS``)."""

    def __init__(self, reason: str, path: str):
        super().__init__(f"{path}: {reason}")
        self.reason, self.path = reason, path


def _special_or_directory(path: str, mode: int) -> Refused:
    return Refused("directory" if stat.S_ISDIR(mode) else "special", path)


def open_regular(path: str, area: Area | None = None, *, follow_links: bool = True) -> int:
    """A descriptor of regular file ``path``, opened for reading without blocking; ``Refused`` when the
    rule refuses it (outside ``area``, a link when ``follow_links`` is false, not a regular file),
    ``OSError`` when it cannot be opened."""
    if "\0" in path:
        raise Refused("name", path)
    if area is not None and not area.holds(path):
        raise Refused("outside", path)
    try:
        info = os.lstat(path) if not follow_links else os.stat(path)
    except FileNotFoundError:
        raise Refused("missing", path) from None
    if stat.S_ISLNK(info.st_mode):
        raise Refused("link", path)
    if not stat.S_ISREG(info.st_mode):
        raise _special_or_directory(path, info.st_mode)
    # (the resolved path is opened with O_NOFOLLOW: a link swapped in after the check is not followed)
    target = os.path.realpath(path) if area is not None or follow_links else path
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(target, flags)
    except FileNotFoundError:
        raise Refused("missing", path) from None
    except OSError as err:
        if os.path.islink(target):  # (ELOOP: a link where none is followed)
            raise Refused("link", path) from err
        raise
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise _special_or_directory(path, mode)
    return fd


def read_regular(path: str, limit: int, area: Area | None = None, *, follow_links: bool = True) -> bytes:
    """At most ``limit`` + 1 bytes of regular file ``path`` (more than ``limit``: the file is too large),
    under the rule of ``open_regular``."""
    fd = open_regular(path, area, follow_links=follow_links)
    with os.fdopen(fd, "rb") as fh:
        return fh.read(limit + 1)


def links_below(directory: str, relative: str) -> str | None:
    """The first symbolic link on the way from ``directory`` to ``relative`` (with "/" separators), the
    file itself included, as a relative path; None when there is none. Generated files are never written
    through a link: one could lead out of the output directory."""
    parts = relative.split("/")
    for n in range(1, len(parts) + 1):
        if os.path.islink(os.path.join(directory, *parts[:n])):
            return "/".join(parts[:n])
    return None


def write_output(path: str, data: str | bytes, *, replace: bool) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` without ever following a symbolic link there: a new
    file (``FileExistsError`` when anything is there, a link included: ``O_EXCL``), or with ``replace``
    a temporary file beside it renamed over what is there (a link is replaced, not written through; a
    regular file keeps its mode). Either the whole file is written or nothing changes."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    if not replace:
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
        fd = os.open(path, flags, 0o666)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(raw)
        except BaseException:  # (the file is ours: O_EXCL made it; nothing of it is left)
            with contextlib.suppress(OSError):
                os.unlink(path)
            raise
        return
    mode = _mode_of(path)
    fd, temporary = tempfile.mkstemp(prefix=".", suffix=".tmp", dir=os.path.dirname(path) or os.curdir)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
        os.chmod(temporary, mode)
        os.replace(temporary, path)
    except BaseException as err:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(err, OSError):  # (named by the file the user asked for, never by the temporary one)
            raise OSError(err.errno, err.strerror, path) from err
        raise


def _mode_of(path: str) -> int:
    """The mode a file written at ``path`` gets: that of the regular file there, else the default."""
    with contextlib.suppress(OSError):
        info = os.lstat(path)
        if stat.S_ISREG(info.st_mode):
            return stat.S_IMODE(info.st_mode)
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask

"""Atomic output files: write to a temporary file, then rename over the target.

Every file geotex writes (meshes, images, ``.npz``, ``.json``) goes through
:func:`atomic_output` or :func:`atomic_group`, so that a failure part way
through never leaves a truncated or half-written file behind: the data is
written to a temporary file in the destination directory (same file system,
so the final :func:`os.replace` is atomic on POSIX and Windows) and is only
renamed onto the target path once everything has been written.  On any
exception (including ``KeyboardInterrupt``) the temporary file is deleted and
the target, if it existed, is left untouched.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from geotex.errors import InputError, MeshFileError

__all__ = ["atomic_output", "atomic_group", "AtomicGroup"]


def _current_umask() -> int:
    """Return the process umask without changing it where the OS allows."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK = _current_umask()


def _open_temp(path: Path, mode: str, encoding, newline):
    """Create and open the temporary sibling of ``path``; return ``(file, name)``."""
    fd, tmp = _create_temp(path)
    os.close(fd)
    try:
        if "b" in mode:
            fh = open(tmp, "wb")
        else:
            fh = open(tmp, "w", encoding=encoding or "utf-8", newline=newline)
    except BaseException:
        _remove_quietly(tmp)
        raise
    return fh, tmp


def _create_temp(path: Path) -> tuple[int, str]:
    """Create the temporary sibling of ``path``; return ``(fd, temp_name)``."""
    directory = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise MeshFileError(path, "cannot write: the path is a directory")
    if not directory.is_dir():
        raise MeshFileError(path, f"cannot write: directory {str(directory)!r} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}",
                                   dir=directory)
    except OSError as exc:
        raise MeshFileError(path, f"cannot write: {exc.strerror or exc}") from None
    return fd, tmp


def _final_mode(path: Path) -> int:
    """Permissions for the output: those of the file replaced, else 0o666 & ~umask."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        return 0o666 & ~_UMASK


def _remove_quietly(name: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(name)


def _commit(tmp: str, path: Path, fsync: bool) -> None:
    """Give ``tmp`` the final permissions and rename it onto ``path``."""
    if fsync:
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    with contextlib.suppress(OSError):
        os.chmod(tmp, _final_mode(path))
    try:
        os.replace(tmp, path)
    except OSError as exc:
        raise MeshFileError(path, f"cannot write: {exc.strerror or exc}") from None


@contextlib.contextmanager
def atomic_output(path, mode: str = "wb", *, encoding: str | None = None,
                  newline: str | None = None, fsync: bool = False):
    """Open a temporary file that replaces ``path`` when the block succeeds.

    Parameters
    ----------
    path : str or os.PathLike
        Final destination.  Its directory must exist.
    mode : {"wb", "w"}, optional
        Binary or text mode.
    encoding, newline : str, optional
        Passed to :func:`open` in text mode (``encoding`` defaults to UTF-8).
    fsync : bool, optional
        Flush the data to disk before the rename (slower, survives power loss).

    Yields
    ------
    file object
        The open temporary file, named ``.STEM.XXXXXX.tmp.EXT`` in the target
        directory: it keeps the target's extension, so writers that infer a
        format from ``fh.name`` (pillow) still work.  Do not close it inside
        the block.

    Raises
    ------
    MeshFileError
        If the directory does not exist, the path is a directory, or the file
        cannot be created or renamed.
    InputError
        If ``mode`` is not a write mode.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> tmp = tempfile.TemporaryDirectory()
    >>> out = pathlib.Path(tmp.name) / "out.json"
    >>> with atomic_output(out, "w") as fh:
    ...     n = fh.write("{}")
    >>> out.read_text()
    '{}'
    >>> tmp.cleanup()
    """
    if mode not in ("w", "wb", "wt"):
        raise InputError(f"atomic_output mode must be 'w' or 'wb', got {mode!r}")
    path = Path(path)
    fh, tmp = _open_temp(path, mode, encoding, newline)
    try:
        with fh:
            yield fh
        _commit(tmp, path, fsync)
    except BaseException:
        _remove_quietly(tmp)
        raise


class AtomicGroup:
    """Several outputs that appear together or not at all; see :func:`atomic_group`."""

    def __init__(self, fsync: bool = False):
        self._fsync = fsync
        self._entries: list[tuple[Path, str, object]] = []

    def open(self, path, mode: str = "wb", *, encoding: str | None = None,
             newline: str | None = None):
        """Return an open temporary file that will become ``path``."""
        if mode not in ("w", "wb", "wt"):
            raise InputError(f"atomic_group mode must be 'w' or 'wb', got {mode!r}")
        path = Path(path)
        if any(p == path for p, _, _ in self._entries):
            raise InputError(f"{path} opened twice in one atomic group")
        fh, tmp = _open_temp(path, mode, encoding, newline)
        self._entries.append((path, tmp, fh))
        return fh

    def _close_all(self) -> None:
        for _, _, fh in self._entries:
            fh.close()

    def _discard(self) -> None:
        for _, tmp, fh in self._entries:
            with contextlib.suppress(Exception):
                fh.close()
            _remove_quietly(tmp)

    def _commit(self) -> None:
        self._close_all()
        done = 0
        try:
            for path, tmp, _ in self._entries:
                _commit(tmp, path, self._fsync)
                done += 1
        finally:
            for _, tmp, _ in self._entries[done:]:
                _remove_quietly(tmp)


@contextlib.contextmanager
def atomic_group(*, fsync: bool = False):
    """Write several files that are renamed into place only if all succeed.

    Used for outputs made of several files, such as an OBJ with its MTL and
    PNG texture.  Every file is written to its own temporary sibling; when the
    block ends without an exception all of them are renamed onto their
    targets, otherwise all temporary files are deleted and no target changes.
    (The renames themselves happen one after the other: a rename failing half
    way, which needs an OS error between two renames in the same directory,
    can leave the earlier files in place.)

    Yields
    ------
    AtomicGroup
        Call ``group.open(path, mode)`` for each output file.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> tmp = tempfile.TemporaryDirectory()
    >>> folder = pathlib.Path(tmp.name)
    >>> with atomic_group() as group:
    ...     n = group.open(folder / "a.obj", "w").write("mtllib a.mtl")
    ...     n = group.open(folder / "a.mtl", "w").write("newmtl m")
    >>> sorted(p.name for p in folder.iterdir())
    ['a.mtl', 'a.obj']
    >>> tmp.cleanup()
    """
    group = AtomicGroup(fsync=fsync)
    try:
        yield group
        group._commit()
    except BaseException:
        group._discard()
        raise

"""Outputs complete only when closed: a ``with`` block closes or aborts them.

:class:`CloseOrAbort` gives a class with ``close()`` (finish: rename the output into place)
and ``abort()`` (remove the partial output) its context-manager methods, so that leaving the
block by an exception leaves nothing half-written; :func:`staging_dir` is the hidden folder
such an output is written into before it is put in place, :class:`StagedFolder` such a
folder's life (every output folder goes through it: a report by :func:`replacing_dir`, a run
by :class:`~twin.formats.runs.RunWriter`) and :func:`replacing_file` the ``with`` block for a single
file. Putting an output in place follows :mod:`twin.core.ownership`: into an existing folder only
the files the twin wrote there are replaced (:func:`install`), and a file replaces only an
earlier output of its kind (or, with ``--overwrite``, a file that is no input). A file that
cannot be written (a full disk, ...) is an :class:`~twin.core.errors.OutputError` naming it by its
final path (:func:`writing`). :func:`check_output_file`, :func:`check_output_dir` and
:func:`check_writable` refuse an output path before any work (the command line calls them
while parsing, :mod:`twin.cli.common`).
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Self

from twin.core.errors import OutputError, UsageError
from twin.core.interrupts import deferred
from twin.core.ownership import (
    MANIFEST,
    check_replace,
    entry,
    input_at,
    kind_of,
    read_manifest,
    real,
    record,
    unchanged,
    write_manifest,
)

#: Errors of writing that the operating system reports without a file name (a full disk or
#: quota, a file too large): in a staged folder they are the folder's.
_UNNAMED_WRITE_ERRORS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def cannot_write(path: str | Path, e: OSError) -> OutputError:
    """Return the error for an output ``path`` the operating system refused to write (``e``)."""
    return OutputError(path, e.strerror or str(e))


@contextmanager
def writing(path: str | Path) -> Iterator[Path]:
    """Yield ``path``; an :class:`OSError` in the block becomes an ``OutputError`` naming it.

    For a file written where the operating system's error would not name it (a write or
    close on a full disk names no file).
    """
    try:
        yield Path(path)
    except OSError as e:
        raise cannot_write(path, e) from None


def staging_dir(final: Path) -> Path:
    """Return a new hidden folder beside ``final`` to write into before renaming it there.

    Made with the permissions a folder made by ``mkdir`` would have (``mkdtemp``'s private
    0700 would otherwise stay on the finished folder).
    """
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=final.parent))
    except OSError as e:
        raise UsageError(f"{final}: cannot be written there ({e.strerror})") from None
    mask = os.umask(0)
    os.umask(mask)
    tmp.chmod(0o777 & ~mask)
    return tmp


def check_writable(final: str | Path) -> Path:
    """Refuse an output path that cannot be created: under a file, or in a folder not writable.

    Looks at the nearest folder that exists (the others are made when the output is written).

    Raises
    ------
    UsageError
        Naming the path and why (a file on the way, permission denied, read-only file system).

    """
    final = Path(final)
    there = next((p for p in final.absolute().parents if p.exists()), None)
    if there is not None and not there.is_dir():
        raise UsageError(f"{final}: {there} is a file, not a folder")
    if there is not None and not os.access(there, os.W_OK | os.X_OK):
        raise UsageError(f"{final}: cannot write in {there} (permission denied or a read-only "
                         "file system)")  # fmt: skip
    return final


def check_output_file(path: str | Path, suffixes: tuple[str, ...] = ()) -> Path:
    """Refuse an output file that cannot be written: a folder, a bad suffix, no way to write.

    Parameters
    ----------
    path : str or Path
        The file to be written.
    suffixes : tuple of str
        Allowed suffixes (lower case, with the dot), e.g. the figure formats; empty: any.

    Raises
    ------
    UsageError
        Naming the path and what is allowed.

    """
    final = Path(path)
    if final.is_dir() or not final.name or str(path).endswith(os.sep):
        raise UsageError(f"{final}: is a folder; give a file name")
    if suffixes and final.suffix.lower() not in suffixes:
        raise UsageError(f"{final}: unknown file type {final.suffix or '(none)'!r}; use one of "
                         f"{', '.join(suffixes)}")  # fmt: skip
    return check_writable(final)


@contextmanager
def replacing_file(final: str | Path, kind: str | None = None) -> Iterator[Path]:
    """Yield a hidden name beside ``final`` (same suffix) that becomes ``final`` on success.

    The file appears under its name only when complete; on an exception the partial file is
    removed. Missing parent folders are made. An existing ``final`` is replaced only as
    :func:`twin.core.ownership.check_replace` allows (an earlier output of the same ``kind``, or
    ``--overwrite``; never an input), and the new file is listed in its folder's manifest.

    Parameters
    ----------
    final : str or Path
        The file to write.
    kind : str, optional
        What kind of output it is (default from its suffix, :func:`twin.core.ownership.kind_of`).

    Raises
    ------
    UsageError
        Before anything is written, for a ``final`` that must not be replaced.

    """
    final = check_output_file(final)
    kind = kind or kind_of(final)
    check_replace(final, kind)
    tmp = final.with_name(f".{final.stem}.partial{final.suffix}")
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        tmp.replace(final)
    except OSError as e:  # named by the user's path, not the hidden one
        with suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise cannot_write(final, e) from None
    except BaseException:
        with suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise
    record(final, kind)


def check_output_dir(final: str | Path, marker: str) -> None:
    """Refuse an output folder :class:`StagedFolder` must not write into (see there).

    Commands call it before their work, so a bad ``--out`` costs nothing.
    """
    final = check_writable(final)
    real(final)  # a link loop is refused by name
    if final.is_symlink():
        raise UsageError(f"output folder {final} is a symbolic link; give the folder itself")
    here = Path.cwd().resolve()
    where = Path(real(final))
    if where == here or where in here.parents:
        raise UsageError(f"output folder {final} is the current folder or above it; give a new "
                         "folder")  # fmt: skip
    if final.exists() and not final.is_dir():
        raise UsageError(f"output folder {final} is a file; give a folder")
    hit = input_at(final)
    if hit is not None:
        what = "is" if real(final) == hit else "lies in"
        raise UsageError(f"output folder {final} {what} an input of this command ({hit}); give "
                         "a new folder")  # fmt: skip
    if not final.is_dir() or not any(p.name != MANIFEST for p in final.iterdir()):
        return
    if read_manifest(final)["kind"] != marker:
        raise UsageError(f"output folder {final} exists and is not an earlier output of this "
                         f"kind (no twin manifest of a {marker} output); give a new folder or "
                         "remove it")  # fmt: skip


def _staged_files(folder: Path, marker: str) -> list[str]:
    """Return every file below ``folder`` by its relative POSIX path, the ``marker`` last.

    Manifests (of nested outputs too) are the twin's bookkeeping, not files of the output:
    they are moved with their folders but not listed.
    """
    found = []
    for here, _dirs, files in os.walk(folder):
        for name in files:
            rel = (Path(here) / name).relative_to(folder).as_posix()
            if rel != f"{MANIFEST}.partial" and name != MANIFEST:
                found.append(rel)
    return sorted(found, key=lambda rel: (rel == marker, rel))


def _manifests(folder: Path) -> list[str]:
    """Return the nested outputs' manifests below ``folder`` (relative POSIX paths)."""
    return sorted((Path(h) / MANIFEST).relative_to(folder).as_posix()
                  for h, _d, names in os.walk(folder)
                  if MANIFEST in names and Path(h) != folder)  # fmt: skip


def _inside(folder: Path, rel: str) -> Path | None:
    """Return ``folder / rel`` if it lies in ``folder`` (links resolved), else None."""
    if Path(rel).is_absolute() or ".." in Path(rel).parts:
        return None
    target = folder / rel
    top = real(folder).rstrip(os.sep) + os.sep
    return target if real(target).startswith(top) else None


def _remove_empty_parents(path: Path, top: Path) -> None:
    """Remove the folders from ``path``'s up to (not including) ``top`` while they are empty.

    A folder that holds nothing but a nested output's manifest is empty too.
    """
    for parent in path.parents:
        if parent == top or top not in parent.parents:
            return
        if [p.name for p in parent.iterdir()] == [MANIFEST]:
            (parent / MANIFEST).unlink()
        try:
            parent.rmdir()
        except OSError:  # not empty: a user's file, or another output's
            return


def refuse_replacing(final: Path, names: list[str], listed: dict, kind: str) -> None:
    """Refuse if any of ``names`` exists in ``final`` and is not an unchanged output of ``kind``.

    Raises
    ------
    UsageError
        Naming the first such file (an input of the command, a file the twin did not write or
        one changed since) and how many more there are.

    """
    refused = []
    for rel in sorted(set(names)):
        if Path(rel).name == MANIFEST:  # a nested output's bookkeeping: always the twin's
            continue
        target = _inside(final, rel)
        if target is None:
            refused.append(f"{final / rel} (outside the folder)")
        elif target.exists() or target.is_symlink():
            if input_at(target) is not None:
                refused.append(f"{target} (an input of this command)")
            elif not unchanged(target, listed.get(rel), kind):
                refused.append(f"{target} (not written by twin, or changed since)")
    if refused:
        more = f" and {len(refused) - 1} more" if len(refused) > 1 else ""
        raise UsageError(f"{final}: the new output would replace {refused[0]}{more}; move it "
                         "away or give another folder")  # fmt: skip


def install(tmp: Path, final: Path, kind: str, reserved: tuple[str, ...] = ()) -> None:
    """Put the complete output folder ``tmp`` in place as ``final`` (see :class:`StagedFolder`).

    A new ``final`` is ``tmp`` renamed. Into an existing one (an earlier output of ``kind``)
    the new files are moved one by one; files the earlier output listed and the new one does
    not write are removed if unchanged and not an input; everything else stays.

    Raises
    ------
    UsageError
        Before anything is moved, where a new file would replace one that is not the twin's
        (or an input), or where a ``reserved`` name is a file the twin did not write.

    """
    new_files = _staged_files(tmp, kind)
    new = {rel: entry(tmp / rel, kind) for rel in new_files}
    if not final.exists():
        write_manifest(tmp, kind, new)
        tmp.replace(final)
        return
    check_output_dir(final, kind)  # it may have changed while the output was made
    listed = read_manifest(final)["files"]
    refuse_replacing(final, [*new_files, *reserved], listed, kind)
    keep, stale = {}, []
    for rel, e in listed.items():
        target = _inside(final, rel)
        if target is None or rel in new or not target.is_file():
            continue
        if e.get("kind") == kind and input_at(target) is None and unchanged(target, e, kind):
            stale.append(target)
        elif unchanged(target, e):
            keep[rel] = e  # another kind of output in this folder, or an input: it stays
    # while files move one by one, the manifest lists old and new: a replacement cut short
    # (a crash; Ctrl-C is held back) leaves every file of it replaceable, the marker last
    during = {**listed, **{rel: {**e, "previous": listed[rel].get("sha256")} if rel in listed
                           else e for rel, e in new.items()}}  # fmt: skip
    with deferred():
        write_manifest(final, kind, during)
        for rel in [*new_files, *_manifests(tmp)]:
            (final / rel).parent.mkdir(parents=True, exist_ok=True)
            (tmp / rel).replace(final / rel)
        for target in stale:
            target.unlink()
            _remove_empty_parents(target, final)
        write_manifest(final, kind, {**keep, **new})
    shutil.rmtree(tmp, ignore_errors=True)


class StagedFolder:
    """An output folder written under a hidden name beside ``final``, put there when complete.

    Parameters
    ----------
    final : str or Path
        The output folder.
    marker : str
        A file every output of this kind holds (e.g. ``report.json``), the kind's name in the
        manifest: an existing ``final`` is written into only if it is empty or an earlier
        output of the same kind, and then only the files that output listed are replaced or
        removed (:func:`install`); a user's files, and the command's inputs, stay.
    reserved : tuple of str
        Names that must not be left in ``final`` unless the twin wrote them (a run's optional
        files: a user's ``actuators.csv`` beside new commands would be read as the run's).

    Attributes
    ----------
    final : Path
        The output folder.
    tmp : Path
        The hidden folder to write into (:func:`staging_dir`).

    Raises
    ------
    UsageError
        Before anything is written, for a ``final`` that is a file, the current folder or one
        above it, an input of the command, or a non-empty folder that is not an earlier output
        of this kind; when finishing, for a new file that would replace one the twin did not
        write.

    """

    def __init__(self, final: str | Path, marker: str, reserved: tuple[str, ...] = ()) -> None:
        self.final = Path(final)
        self.marker = marker
        self.reserved = reserved
        check_output_dir(self.final, marker)
        if reserved and self.final.is_dir():
            refuse_replacing(self.final, list(reserved), read_manifest(self.final)["files"],
                             marker)  # fmt: skip
        self.tmp = staging_dir(self.final)

    def finish(self) -> None:
        """Put the complete folder in place as ``final`` (:func:`install`)."""
        install(self.tmp, self.final, self.marker, self.reserved)

    def discard(self) -> None:
        """Remove the hidden folder and all written into it."""
        shutil.rmtree(self.tmp, ignore_errors=True)

    @contextmanager
    def removed_on_error(self) -> Iterator[None]:
        """Discard the folder if the block raises; name a failed write by its final path.

        An :class:`OSError` of a file in the hidden folder, or one that names no file but is
        a full disk (:data:`_UNNAMED_WRITE_ERRORS`), becomes an ``OutputError`` naming the file
        (or ``final``) where the user will look for it; an ``OutputError`` for a path in the
        hidden folder (a staged output within this one) is named there too. Other errors
        (an input that cannot be read, ...) pass as they are.
        """
        try:
            yield
        except BaseException as e:
            self.discard()
            named = self._named(e)
            if named is None:
                raise
            raise named from None

    def _named(self, e: BaseException) -> OutputError | None:
        """Return ``e`` as an ``OutputError`` naming the final path, or None to keep ``e``."""
        if isinstance(e, OutputError):
            path, reason = e.path, e.reason
        elif isinstance(e, OSError):
            path, reason = e.filename, e.strerror or str(e)
            if path is None and e.errno in _UNNAMED_WRITE_ERRORS:
                return OutputError(self.final, reason)
        else:
            return None
        if not isinstance(path, str | os.PathLike) or not Path(path).is_relative_to(self.tmp):
            return None
        return OutputError(self.final / Path(path).relative_to(self.tmp), reason)


@contextmanager
def replacing_dir(final: str | Path, marker: str) -> Iterator[Path]:
    """Yield a staging folder that replaces ``final`` when the block ends without an error.

    On an error the staging folder is removed; a file that could not be written is named by
    its final path (:meth:`StagedFolder.removed_on_error`).

    Parameters
    ----------
    final : str or Path
        The output folder.
    marker : str
        A file every output of this kind holds (see :class:`StagedFolder`).

    Raises
    ------
    UsageError
        Before anything is written, for a ``final`` that cannot be replaced (see
        :class:`StagedFolder`).
    OutputError
        For a file or folder that could not be written.

    """
    staged = StagedFolder(final, marker)
    with staged.removed_on_error():
        yield staged.tmp
        staged.finish()


class CloseOrAbort(ABC):
    """Base: ``with obj:`` calls ``obj.close()``, or ``obj.abort()`` on an exception."""

    @abstractmethod
    def close(self) -> None:
        """Finish the output."""

    @abstractmethod
    def abort(self) -> None:
        """Remove the partial output."""

    def __enter__(self) -> Self:
        """Enter the context."""
        return self

    def __exit__(self, kind: object, exc: object, tb: object) -> None:
        """Close, or abort on an exception (also one of closing: a full disk, ...)."""
        if kind is not None:
            self.abort()
            return
        try:
            self.close()
        except BaseException:
            self.abort()
            raise

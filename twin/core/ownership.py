"""What the twin wrote, and what a command reads: the rule that keeps a user's data safe.

The rule, in one place for every output:

- An output never deletes or replaces an **input** of the same command (:func:`inputs`),
  nor any file or folder the twin did not write.
- What the twin wrote is listed in a **manifest**, a hidden ``.twin-manifest.json`` in the
  folder it wrote into: each file by its path relative to that folder, the *kind* of output
  it belongs to and its SHA-256. A file is the twin's (:func:`owned`) only while it is listed
  and unchanged: a file a user edited is the user's again.
- A folder output (a report, a run) replaces only the files its earlier output of the same
  kind listed, and keeps everything else (:func:`twin.core.lifecycle.StagedFolder`).
- A single-file output (a figure, a recording, a configuration) replaces an existing file only
  if it is an earlier output of the same kind, or when the command was given ``--overwrite``
  (:func:`overwrite`) — and never an input, ``--overwrite`` or not (:func:`check_replace`).

:func:`output_policy` sets a command's inputs and its ``--overwrite`` for the code it calls
(the command line sets them once per command, :func:`twin.cli.main.main`); library callers
may set them too, and get the safe defaults (no input known, no ``--overwrite``) otherwise.
"""

from __future__ import annotations

import contextvars
import errno
import hashlib
import json
import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path

from twin.core.errors import UsageError
from twin.core.version import __version__

#: The manifest's file name in every folder the twin wrote into.
MANIFEST = ".twin-manifest.json"
#: The manifest's format tag.
MANIFEST_FORMAT = "twin-manifest/1"
#: Kinds of single-file outputs by suffix (a figure, a recording, ...); others: the suffix.
FILE_KINDS = {".rrd": "recording", ".json": "json", ".csv": "table", ".md": "text"}
_FIGURES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".tif", ".tiff", ".webp",
            ".eps", ".ps")  # fmt: skip


@dataclass(frozen=True)
class Policy:
    """A command's inputs (real paths) and whether it may overwrite files it did not write."""

    overwrite: bool = False
    inputs: tuple[str, ...] = ()


_SAFE = Policy()
_POLICY: contextvars.ContextVar[Policy | None] = contextvars.ContextVar("twin_output_policy",
                                                                        default=None)  # fmt: skip


def policy() -> Policy:
    """Return the running command's policy (the safe default outside :func:`output_policy`)."""
    return _POLICY.get() or _SAFE


def real(path: str | Path) -> str:
    """Return the real path of ``path`` (links resolved), or refuse a link loop.

    Raises
    ------
    UsageError
        For a path through a symbolic-link loop (it names no file that can be written).

    """
    try:
        os.stat(path)
    except OSError as e:
        if e.errno == errno.ELOOP:
            raise UsageError(f"{path}: a symbolic-link loop; give a real path") from None
    except ValueError:  # an embedded NUL byte
        raise UsageError(f"{path!r}: not a valid path") from None
    return os.path.realpath(path)


@contextmanager
def output_policy(
    *, overwrite: bool = False, inputs: Iterable[str | Path] = ()
) -> Iterator[Policy]:
    """Within the block, outputs respect ``inputs`` and ``overwrite`` (see the module docstring).

    Parameters
    ----------
    overwrite : bool
        A single-file output may replace an existing file the twin did not write (never an
        input).
    inputs : iterable of str or Path
        Files and folders the command reads: never replaced or deleted, nor anything in them.

    """
    now = Policy(bool(overwrite), tuple(real(p) for p in inputs))
    token = _POLICY.set(now)
    try:
        yield now
    finally:
        _POLICY.reset(token)


@contextmanager
def reading(*paths: str | Path) -> Iterator[Policy]:
    """Within the block, ``paths`` are inputs too (a library function that reads and writes).

    Keeps the running command's ``--overwrite`` and inputs (:func:`output_policy`).
    """
    now = policy()
    with output_policy(overwrite=now.overwrite, inputs=[*now.inputs, *paths]) as extended:
        yield extended


def overwrite() -> bool:
    """Return whether the running command may overwrite files it did not write."""
    return policy().overwrite


def input_at(path: str | Path) -> str | None:
    """Return the input that ``path`` is or lies in (None: it touches no input)."""
    p = real(path)
    for i in policy().inputs:
        if p == i or p.startswith(i.rstrip(os.sep) + os.sep):
            return i
    return None


def kind_of(path: str | Path) -> str:
    """Return the default kind of a single-file output, from its suffix."""
    suffix = Path(path).suffix.lower()
    return "figure" if suffix in _FIGURES else FILE_KINDS.get(suffix, suffix or "file")


def digest(path: str | Path) -> str:
    """Return the SHA-256 of a file, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_manifest(folder: str | Path) -> dict:
    """Return the manifest of ``folder``: ``{"kind": str or None, "files": {rel: entry}}``.

    A folder without one (or with one that is not a manifest) lists nothing: nothing in it is
    the twin's.
    """
    empty: dict = {"kind": None, "files": {}}
    try:
        data = json.loads((Path(folder) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return empty
    if not isinstance(data, dict) or data.get("format") != MANIFEST_FORMAT:
        return empty
    files = data.get("files")
    if not isinstance(files, dict) or not all(isinstance(v, dict) for v in files.values()):
        return empty
    kind = data.get("kind")
    return {"kind": kind if isinstance(kind, str) else None, "files": files}


def write_manifest(folder: str | Path, kind: str | None, files: dict[str, dict]) -> None:
    """Write the manifest of ``folder`` (under a hidden name, then renamed)."""
    folder = Path(folder)
    data = {"format": MANIFEST_FORMAT, "written_by": f"twin {__version__}", "kind": kind,
            "files": dict(sorted(files.items()))}  # fmt: skip
    tmp = folder / f"{MANIFEST}.partial"
    tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    tmp.replace(folder / MANIFEST)


def entry(path: str | Path, kind: str) -> dict:
    """Return a manifest entry of the file at ``path`` (its kind and SHA-256)."""
    return {"kind": kind, "sha256": digest(path)}


def unchanged(path: Path, listed: dict | None, kind: str | None = None) -> bool:
    """Return whether ``path`` is a file the twin wrote as ``listed`` (of ``kind``), unchanged.

    An entry may also name the ``previous`` content of its path: while an output replaces an
    earlier one file by file, either is the twin's (a replacement cut short stays replaceable).
    """
    if listed is None or (kind is not None and listed.get("kind") != kind):
        return False
    if path.is_symlink() or not path.is_file():
        return False
    try:
        return digest(path) in (listed.get("sha256"), listed.get("previous"))
    except OSError:
        return False


def owned(path: str | Path, kind: str | None = None) -> bool:
    """Return whether the file at ``path`` is an unchanged output of the twin (of ``kind``).

    Looks in the manifest of the file's folder.
    """
    p = Path(path)
    return unchanged(p, read_manifest(p.parent)["files"].get(p.name), kind)


def record(path: str | Path, kind: str) -> None:
    """List the file just written at ``path`` in its folder's manifest, as of ``kind``.

    A failure to list it is not an error of the output (the file is complete); it only means
    a later run will treat the file as not the twin's.
    """
    p = Path(path)
    m = read_manifest(p.parent)
    with suppress(OSError):
        m["files"][p.name] = entry(p, kind)
        write_manifest(p.parent, m["kind"], m["files"])


def check_replace(path: str | Path, kind: str) -> None:
    """Refuse to write a single file at ``path`` if that would replace what it must not.

    Allowed: a new file; an existing file that is an earlier output of the same ``kind``
    (listed, unchanged); any existing file under ``--overwrite`` (:func:`overwrite`). Never an
    input of the command, nor a file inside an input folder (not even a new one: the input
    stays as the user gave it).

    Raises
    ------
    UsageError
        Naming the file and what to do instead.

    """
    p = Path(path)
    hit = input_at(p)
    if hit is not None:
        what = "is" if real(p) == hit else "lies in"
        raise UsageError(f"{path}: {what} an input of this command ({hit}); give another output "
                         "name")  # fmt: skip
    if not (p.exists() or p.is_symlink()) or owned(p, kind) or overwrite():
        return
    raise UsageError(f"{path}: exists and is not an earlier {kind} output of twin; give another "
                     "name, or --overwrite to replace it")  # fmt: skip

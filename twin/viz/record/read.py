"""Reading ``.rrd`` files back: which entities and archetypes they hold (checks and tests)."""

from __future__ import annotations

from pathlib import Path


def read_entities(path: str | Path) -> dict[str, int]:
    """Return {entity path: number of logged rows} of an ``.rrd`` file."""
    from rerun.chunk import RrdReader

    counts: dict[str, int] = {}
    for chunk in RrdReader(str(path)).stream():
        counts[chunk.entity_path] = counts.get(chunk.entity_path, 0) + chunk.num_rows
    return counts


def read_archetypes(path: str | Path) -> dict[str, set[str]]:
    """Return {entity path: names of the archetypes logged there} of an ``.rrd`` file.

    Names are rerun's without the package (``Transform3D``, ``Boxes3D``, ``Scalars``, ...).
    """
    from rerun.chunk import RrdReader

    out: dict[str, set[str]] = {}
    for chunk in RrdReader(str(path)).stream():
        names = out.setdefault(chunk.entity_path, set())
        for field in chunk.to_record_batch().schema:
            archetype = (field.metadata or {}).get(b"rerun:archetype")
            if archetype:
                names.add(archetype.decode().rsplit(".", 1)[-1])
    return out


def read_timelines(path: str | Path) -> dict[str, set[str]]:
    """Return {entity path: names of the timelines its non-static rows are indexed by}."""
    from rerun.chunk import RrdReader

    out: dict[str, set[str]] = {}
    for chunk in RrdReader(str(path)).stream():
        names = out.setdefault(chunk.entity_path, set())
        for field in chunk.to_record_batch().schema:
            if (field.metadata or {}).get(b"rerun:kind") == b"index":
                names.add(field.name)
    return out

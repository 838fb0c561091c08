"""Populations with planted effects, in place of flying subjects (tests of the statistics)."""

from __future__ import annotations

import numpy as np

from twin.core.thesis import TABLE_6_3, TABLES_6_4_TO_6_7
from twin.pilot.studies.population import COMPARED, levels

#: Noise per cell of the planted rows; a factor's marginal means (four cells each) then differ
#: by noise of sd NOISE * sqrt(1 / 2) per subject.
NOISE = 0.3


def planted_rows(seed: int, subjects: int = 9, reversed_measure: str = "k_v") -> list[dict]:
    """Rows with every filter effect planted at the thesis' own standardised size and direction
    (d_z = sqrt(F / 9): the effect is d_z times the marginal difference's noise sd), no delay
    or noise effect, and ``reversed_measure``'s filter effect reversed; subject offsets sd 1."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(1, subjects + 1):
        offset = rng.normal(0, 1)
        for n in TABLE_6_3:
            lv = levels(n)
            values = {}
            for m in COMPARED:
                f, direction = TABLES_6_4_TO_6_7[m]["filter"]
                size = np.sqrt(f / 9) * NOISE * np.sqrt(0.5) * (-1.0 if direction == "-" else 1.0)
                size *= -1.0 if m == reversed_measure else 1.0
                values[m] = offset + size * lv["filter"] + rng.normal(0, NOISE)
            rows.append({"subject": s, "condition": n, **lv, **values})
    return rows

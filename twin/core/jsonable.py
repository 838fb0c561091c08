"""Values ready for strict JSON: Python scalars, lists and dicts, None for NaN and infinity.

>>> import numpy as np
>>> plain({"a": np.float64(1.5), "b": [np.inf, np.int64(2)], 3: (True, np.nan)})
{'a': 1.5, 'b': [None, 2], '3': [True, None]}

"""

from __future__ import annotations

import numpy as np


def plain(v: object) -> object:
    """Turn numpy scalars into Python ones and NaN/inf into None, recursively."""
    if isinstance(v, dict):
        return {str(k): plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [plain(x) for x in v]
    if isinstance(v, np.ndarray):
        return plain(v.tolist())
    if isinstance(v, bool | np.bool_):
        return bool(v)
    if isinstance(v, int | np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        return float(v) if np.isfinite(v) else None
    return v

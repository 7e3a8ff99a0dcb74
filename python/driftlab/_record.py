"""The Python class of driftlab's typed records (a run's, an evaluation's, a sweep's)."""

import math
import types


class Record(types.SimpleNamespace):
    """One typed record: its attributes are the keys of the file it is written to
    (docs/metrics-reference.md); a number that could not be computed is NaN."""

    def to_dict(self):
        """The record as plain dicts, lists and numbers (NaN stays NaN)."""
        return _plain(self)

    def keys(self):
        return list(vars(self))


def _plain(value):
    if isinstance(value, Record):
        return {k: _plain(v) for k, v in vars(value).items()}
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def isnan(value):
    """Whether a record's number is missing (NaN)."""
    return isinstance(value, float) and math.isnan(value)

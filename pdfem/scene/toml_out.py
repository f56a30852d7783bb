"""A small TOML writer for resolved scenes (``tomllib`` reads but cannot write).

Handles what a resolved scene holds: nested tables, arrays of tables, and inline arrays of
strings, ints and floats. Floats are written with ``repr`` (shortest exact round trip), so
``tomllib.loads(dumps(d)) == d``.
"""

import json
import math
import re

_BARE = re.compile(r"[A-Za-z0-9_-]+")


def dumps(doc, header=""):
    """TOML text of ``doc`` (a dict); ``header`` lines are prepended as # comments."""
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    _table(doc, [], lines, array_item=False)
    return "\n".join(lines).lstrip("\n") + "\n"


def _is_table_array(v):
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _table(tbl, path, lines, array_item):
    """Emit one table: its header, its plain values, then its sub-tables and arrays."""
    plain = {k: v for k, v in tbl.items() if not isinstance(v, dict) and not _is_table_array(v)}
    # The header (implied by sub-table headers when the table has no plain values)
    if path and (array_item or plain or len(plain) == len(tbl)):
        name = ".".join(_key(k) for k in path)
        lines += ["", f"[[{name}]]" if array_item else f"[{name}]"]
    # Plain values before any sub-table header
    for k, v in plain.items():
        lines.append(f"{_key(k)} = {_value(v)}")
    # Sub-tables and arrays of tables, in order
    for k, v in tbl.items():
        if isinstance(v, dict):
            _table(v, path + [k], lines, array_item=False)
        elif k not in plain:
            for item in v:
                _table(item, path + [k], lines, array_item=True)


def _key(k):
    """A bare key when possible, else a quoted one."""
    return k if _BARE.fullmatch(k) else _string(k)


def _string(s):
    """A TOML basic string (JSON escapes are valid TOML escapes; DEL must be escaped)."""
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v):
    """An inline TOML value."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return repr(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")

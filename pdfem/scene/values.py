"""Checking one table against its :class:`~pdfem.scene.schema.Key` specs.

Errors are :class:`SceneError` carrying the key path (``time.end``, ``grains[3].axes``);
:func:`pdfem.scene.parse_scene` prefixes the file name and raises ``InputError``.
"""

import math
import re

from pdfem.errors import SceneError
from pdfem.scene.schema import OPTIONAL, REQUIRED, Derived

_BARE = re.compile(r"[A-Za-z0-9_-]+")


def join(path, key):
    """Key path of ``key`` inside ``path``, quoting keys that are not bare TOML keys."""
    k = key if _BARE.fullmatch(key) else '"' + key.replace('"', '\\"') + '"'
    return f"{path}.{k}" if path else k


def show(value):
    """A short one-line rendering of a user value for an error message."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _Bad(Exception):
    """A bad value, before its key path is known (paths are built only on error)."""

    def __init__(self, msg, index=None):
        super().__init__(msg)
        self.msg, self.index = msg, index


def _number(value, key):
    """``value`` as a finite float (ints accepted; bools, strings, nan, -inf rejected)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _Bad(f"expected a number (got {show(value)})")
    x = float(value)
    if x != x or (x in (math.inf, -math.inf) and not (key.allow_inf and x > 0)):
        raise _Bad(f"must be finite (got {show(x)})")
    return x


def _in_range(x, key):
    """Raise unless ``x`` lies in the key's [lo, hi] (open ends as declared)."""
    low = key.lo is not None and (x <= key.lo if key.lo_open else x < key.lo)
    high = key.hi is not None and (x >= key.hi if key.hi_open else x > key.hi)
    if low or high:
        why = f": {key.why}" if key.why else ""
        text = key.range_text()
        text = "in " + text if text[:1] in "([" else text
        raise _Bad(f"must be {text} (got {show(x)}){why}")


def _vector(value, n, key):
    """A list of ``n`` finite numbers, each in the key's range."""
    if not isinstance(value, list) or len(value) != n:
        shape = "[x, y]" if n == 2 else "[x0, y0, x1, y1]"
        raise _Bad(f"expected {shape} ({n} numbers) (got {show(value)})")
    out = []
    for i, v in enumerate(value):
        try:
            x = _number(v, key)
            _in_range(x, key)
        except _Bad as exc:
            raise _Bad(exc.msg, i) from None
        out.append(x)
    return out


def _choice(s, key):
    """A string among the key's choices (when it has any)."""
    if key.choices and s not in key.choices:
        raise _Bad(f"must be {key.range_text()} (got {show(s)})")
    return s


def _string(value):
    if not isinstance(value, str):
        raise _Bad(f"expected a string (got {show(value)})")
    return value


def _check(value, key):
    """Convert and check one value; returns plain Python (float, int, str, list)."""
    kind = key.kind
    # Scalars
    if kind == "float":
        x = _number(value, key)
        _in_range(x, key)
        return x
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise _Bad(f"expected an integer (got {show(value)})")
        _in_range(int(value), key)
        return int(value)
    if kind == "str":
        return _choice(_string(value), key)
    if kind == "bool":
        if not isinstance(value, bool):
            raise _Bad(f"expected true or false (got {show(value)})")
        return value
    # Vectors
    if kind == "vec2":
        return _vector(value, 2, key)
    if kind == "box":
        box = _vector(value, 4, key)
        if not (box[2] > box[0] and box[3] > box[1]):
            raise _Bad(f"needs x1 > x0 and y1 > y0 (got {show(box)})")
        return box
    # Lists of strings
    if kind == "strlist":
        if not isinstance(value, list):
            raise _Bad(f"expected a list of strings (got {show(value)})")
        out = []
        for i, v in enumerate(value):
            try:
                out.append(_choice(_string(v), key))
            except _Bad as exc:
                raise _Bad(exc.msg, i) from None
            if v in out[:i]:
                raise _Bad(f"{show(v)} is listed twice", i)
        return out
    raise AssertionError(f"unknown key kind {kind!r}")


def _located(exc, path):
    """The SceneError of a _Bad value found at ``path``."""
    return SceneError(path if exc.index is None else f"{path}[{exc.index}]", exc.msg)


def table(value, path, what="a table"):
    """``value`` if it is a TOML table (dict), else an error naming ``path``."""
    if not isinstance(value, dict):
        raise SceneError(path, f"expected {what} (got {show(value)})")
    return value


def check_table(value, keys, path, hint=""):
    """Check a table against ``keys`` (name -> Key): unknown, missing, type, range.

    Returns a new dict in the order of ``keys`` with plain defaults filled in; keys whose
    default is OPTIONAL or :class:`Derived` stay absent when not given.
    """
    tbl = table(value, path)
    # Unknown keys first: a misspelt key usually explains a missing one
    for name in tbl:
        if name not in keys:
            known = ", ".join(keys)
            raise SceneError(join(path, name), f"unknown key{hint} (known: {known})")
    out = {}
    for name, key in keys.items():
        if name in tbl:
            try:
                out[name] = _check(tbl[name], key)
            except _Bad as exc:
                raise _located(exc, join(path, name)) from None
        elif key.default is REQUIRED:
            raise SceneError(join(path, name), "required key missing")
        elif key.default is OPTIONAL or isinstance(key.default, Derived):
            continue
        else:
            d = key.default
            out[name] = list(d) if isinstance(d, list) else d
    return out


def array_of_tables(value, path):
    """``value`` as a list of tables (TOML ``[[path]]``)."""
    if not isinstance(value, list):
        raise SceneError(path, f"expected an array of tables [[{path}]] (got {show(value)})")
    for i, item in enumerate(value):
        table(item, f"{path}[{i}]")
    return value

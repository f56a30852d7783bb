"""Mutations of a scene for the fuzz tests: one key or table deleted, a value replaced by a
wrong type, a negative, zero, NaN, infinite, huge or empty value, a value scaled, an unknown
key or table added, the text cut short or spliced with garbage."""

import math
import tomllib

from hypothesis import strategies as st

from pdfem.scene.toml_out import dumps

# Replacement values: wrong types, signs, zero, non-finite, huge, empty
BAD_VALUES = ["text", "", True, [], {}, [1.0], [1.0, 2.0, 3.0], -1.0, -1, 0, 0.0, math.nan,
              math.inf, -math.inf, 1.0e300, -1.0e300, 10**12, 2**70, 1.0e-300]
# Factors on a number (or every number of a list): still valid or just out of range (an
# integer such as a block's nx only grows to what stays a small run, or far beyond the limit)
FACTORS = [-1.0, 0.0, 1.0e-6, 0.5, 2.0, 1.0e6, 1.0e300]
INT_FACTORS = [-1, 0, 2, 10**12]
# Unknown names, some one typo away from a real key or effect
UNKNOWN = ["bogus", "gama", "viscosityy", "frictional_heating", "heat_", "Domain", "x y",
           "__import__", "!!python/object"]


def _paths(node, path=()):
    """Every key path (tuple of keys and list indices) inside a parsed TOML document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for k, v in items:
        yield path + (k,)
        yield from _paths(v, path + (k,))


def _parent(doc, path):
    for k in path[:-1]:
        doc = doc[k]
    return doc


def _scaled(v, k):
    """``v`` (a number or a list of them) scaled by FACTORS[k] or, an integer, INT_FACTORS."""
    if isinstance(v, list):
        return [_scaled(x, k) for x in v]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return v
    return v * (INT_FACTORS[k % len(INT_FACTORS)] if isinstance(v, int) else FACTORS[k])


@st.composite
def mutants(draw, base):
    """(file bytes, what was done) of the scene text ``base`` mutated once."""
    doc = tomllib.loads(base)
    text = dumps(doc)
    kind = draw(st.sampled_from(["replace", "replace", "scale", "delete", "unknown key",
                                 "unknown table", "truncate", "garbage"]))
    if kind == "truncate":
        k = draw(st.integers(0, len(text) - 1))
        return text[:k].encode(), f"truncated at {k}"
    if kind == "garbage":
        junk = draw(st.sampled_from([b"\x89HDF\r\n\x1a\n\x00\x00", bytes(range(256)),
                                     b"[[[", b"= 1", b"a = \"unterminated", b"\xff\xfe"]))
        k = draw(st.integers(0, len(text)))
        return text[:k].encode() + junk + text[k:].encode(), f"garbage at {k}"
    if kind == "unknown table":
        name = draw(st.sampled_from(UNKNOWN))
        doc[name] = {"x": 1.0}
        return dumps(doc).encode(), f"table [{name}]"
    path = draw(st.sampled_from(list(_paths(doc))))
    parent = _parent(doc, path)
    if kind == "delete":
        del parent[path[-1]]
    elif kind == "unknown key":
        target = parent[path[-1]]
        tables = target if isinstance(target, dict) else parent if isinstance(parent, dict) \
            else None
        if tables is None:
            return text.encode(), "unchanged"
        tables[draw(st.sampled_from(UNKNOWN))] = 1.0
    elif kind == "scale":
        parent[path[-1]] = _scaled(parent[path[-1]], draw(st.integers(0, len(FACTORS) - 1)))
    else:
        # An item of an array of tables stays a table (the TOML writer has no inline tables)
        values = BAD_VALUES if isinstance(parent, dict) else [{}, {"bogus": 1.0}] \
            if all(isinstance(x, dict) for x in parent) else BAD_VALUES[:4] + BAD_VALUES[5:]
        parent[path[-1]] = draw(st.sampled_from(values))
    return dumps(doc).encode(), f"{kind} {'.'.join(map(str, path))}"

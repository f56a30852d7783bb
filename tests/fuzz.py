"""Mutations of a scene for the fuzz tests: one key or table deleted, a value replaced by a
wrong type, a negative, zero, NaN, infinite, huge or empty value, a value scaled, an unknown
key or table added, the text cut short or spliced with garbage, or a key that sets a schedule
(an interval, an end, a release or ramp time) given a subnormal, tiny or extreme time."""

import contextlib
import math
import signal
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
# The keys that set a schedule: (table, key) of a scene, and the keys of a [[bc]] item
SCHEDULE_KEYS = [("time", "end"), ("output", "interval"), ("output", "energy_interval"),
                 ("output", "gauge_interval"), ("output", "checkpoint_interval"),
                 ("output", "checkpoint_wall"), ("prepare", "phase_time")]
BC_SCHEDULE_KEYS = ["release", "ramp_down"]
# Times for them [s]: the smallest subnormal and others, the smallest normal float, tiny
# intervals (far below a step, or below the time's own resolution), a step or so, the end
# of a short run, and huge ones
EXTREME_TIMES = [5.0e-324, 1.0e-320, 2.2250738585072014e-308, 1.0e-300, 1.0e-20, 1.0e-15,
                 1.0e-12, 1.0e-9, 1.0e-8, 1.0e-3, 1.0e300, 1.7976931348623157e308]


class Hang(Exception):
    """A command ran past its alarm."""


@contextlib.contextmanager
def alarm(seconds):
    """Raise Hang in the main thread after ``seconds`` (a hang fails instead of blocking)."""
    def ring(signum, frame):
        raise Hang(f"still running after {seconds} s")
    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


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


def schedule_keys(doc):
    """The schedule keys the scene doc can hold, as key paths: those of SCHEDULE_KEYS whose
    table it has, and release and ramp_down of each [[bc]] item."""
    keys = [(t, k) for t, k in SCHEDULE_KEYS if isinstance(doc.get(t), dict)]
    for i, bc in enumerate(doc.get("bc", []) if isinstance(doc.get("bc"), list) else []):
        keys += [("bc", i, k) for k in BC_SCHEDULE_KEYS if isinstance(bc, dict)]
    return keys


def schedule_name(path):
    """A schedule key path as messages name it: output.interval, bc[1].release."""
    if path[0] == "bc":
        return f"bc[{path[1]}].{path[2]}"
    return ".".join(path)


@st.composite
def schedule_mutants(draw, base):
    """(file bytes, key name, value) of the scene text ``base`` with one schedule key (set or
    not) given one of EXTREME_TIMES."""
    doc = tomllib.loads(base)
    path = draw(st.sampled_from(schedule_keys(doc)))
    value = draw(st.sampled_from(EXTREME_TIMES))
    _parent(doc, path)[path[-1]] = value
    return dumps(doc).encode(), schedule_name(path), value


@st.composite
def mutants(draw, base):
    """(file bytes, what was done) of the scene text ``base`` mutated once."""
    doc = tomllib.loads(base)
    text = dumps(doc)
    kind = draw(st.sampled_from(["replace", "replace", "scale", "delete", "unknown key",
                                 "unknown table", "truncate", "garbage", "schedule"]))
    if kind == "schedule" and schedule_keys(doc):
        data, name, value = draw(schedule_mutants(base))
        return data, f"schedule {name} = {value!r}"
    if kind == "schedule":
        return text.encode(), "unchanged"
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

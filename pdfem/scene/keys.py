"""What a scene key and a scene table are: :class:`Key`, :class:`Section`, the default markers
and the constructors of positive and non-negative numbers. The tables themselves are in
:mod:`pdfem.scene.schema`.
"""

from dataclasses import dataclass, field


class _Marker:
    """A named sentinel for defaults that are not values."""

    def __init__(self, name):
        self.name = name

    def __repr__(self):
        return self.name


# The key must be given
REQUIRED = _Marker("REQUIRED")
# The key may be absent and stays absent in the resolved scene
OPTIONAL = _Marker("OPTIONAL")


@dataclass(frozen=True)
class Derived:
    """A default computed from other keys by :mod:`pdfem.scene.validate`; ``text`` says how."""

    text: str


@dataclass(frozen=True)
class Key:
    """One scene key: its kind, default and range, with the documentation of each.

    kind: ``float``, ``int``, ``str``, ``vec2`` ([x, y]), ``box`` ([x0, y0, x1, y1]) or
    ``strlist``. ``lo``/``hi`` bound numbers (every component of a vector), open when
    ``lo_open``/``hi_open``; ``choices`` restricts strings (each element of a strlist).
    ``allow_inf`` lets +inf through the finiteness check. ``why`` is appended to a range error.
    """

    kind: str
    default: object = REQUIRED
    doc: str = ""
    units: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    allow_inf: bool = False
    why: str = ""

    def range_text(self):
        """The allowed range in words: ``> 0``, ``[0, 0.5]``, ``one of "a", "b"``."""
        if self.choices:
            word = "each one of " if self.kind == "strlist" else "one of "
            return word + ", ".join(f'"{c}"' for c in self.choices)
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            left, right = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
            return f"{left}{_num(lo)}, {_num(hi)}{right}"
        if lo is not None:
            return f"{'>' if self.lo_open else '>='} {_num(lo)}"
        if hi is not None:
            return f"{'<' if self.hi_open else '<='} {_num(hi)}"
        return ""


def _num(x):
    return repr(int(x)) if float(x).is_integer() and abs(x) < 1e15 else repr(x)


def _pos(kind="float", default=REQUIRED, doc="", units="", **kw):
    """A number > 0."""
    return Key(kind, default, doc, units, lo=0.0, lo_open=True, **kw)


def _nonneg(kind="float", default=REQUIRED, doc="", units="", **kw):
    """A number >= 0."""
    return Key(kind, default, doc, units, lo=0.0, **kw)


@dataclass(frozen=True)
class Section:
    """A scene table. form: ``table``, ``array`` ([[name]]) or ``named`` ([name.NAME])."""

    name: str
    form: str
    doc: str
    keys: dict = field(default_factory=dict)
    required: bool = False

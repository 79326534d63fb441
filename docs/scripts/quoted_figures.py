"""Check the figures quoted in README.md and docs/*.md against ``benchmarks/results/*.json``.

A figure that a benchmark measures carries a marker right after it (units may stand between)::

    0.10 s CPU per cycle <!-- fig: sim_cycle.json:figures/cpu_seconds_per_cycle_20x200 -->

The marker names the results file and the path of the value in it (keys joined by ``/``, list
items by their index; keys may contain dots and spaces). An optional factor converts the JSON
value to the quoted unit, e.g. ``<!-- fig: sim_cycle.json:figures/x_s *1e3 -->`` for a figure
quoted in milliseconds. The figure is the last number before the marker; it agrees when it
equals the JSON value rounded to the digits the figure shows (half a unit of its last digit).

A range's ends are the least or the largest of several values: a path step ``*`` takes every
key (or item) at that level, ``(a|b|c)`` the keys named, ``[key=value,key^=text,key$=text]``
the items of a list of records whose fields equal (begin with, end with) the texts given, and
``min`` or ``max`` after the path says which end is quoted::

    8 <!-- fig: sim_rigs.json:figures/rigs/(default|friction_0)/cpu_s min -->–21 s
    <!-- fig: sim_rigs.json:figures/rigs/(default|friction_0)/cpu_s max -->

A path that names several values without ``min`` or ``max`` is reported, as is ``min``/``max``
on a path that names one.

Usage: ``python docs/scripts/quoted_figures.py`` prints every marked figure with its JSON value
and exits 1 when one disagrees or its marker names no value.
"""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"

MARKER = re.compile(
    r"<!--\s*fig:\s*(?P<file>[\w.-]+\.json):(?P<path>[^>]+?)(?:\s+(?P<end>min|max))?"
    r"\s*(?:\*\s*(?P<factor>[-+0-9.eE]+)\s*)?-->"
)
# a number as docs write it: 1.71, 0.10, 2,909, 1e-16, −0.5 (unicode minus)
NUMBER = re.compile(r"[-−]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?:[eE][-−+]?\d+)?")


@dataclass(frozen=True)
class Figure:
    """One marked figure: where it is, what it says, and what its JSON value is."""

    doc: str
    line: int
    quoted: str
    source: str
    value: float | None
    problem: str | None

    @property
    def ok(self) -> bool:
        return self.problem is None


def documents(root: Path = ROOT) -> list[Path]:
    """README.md and docs/*.md."""
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def _child(data: object, key: str) -> object:
    if isinstance(data, list):
        return data[int(key)]
    if isinstance(data, dict):
        return data[key]
    raise KeyError(key)


#: Field tests of a record filter: ``key^=text`` begins with, ``key$=text`` ends with.
_FIELD_TESTS = {"^": str.startswith, "$": str.endswith}


def _matches(record: object, conditions: str) -> bool:
    """``record`` (a dict) has every field of ``conditions`` (``key=value`` equal, ``key^=text``
    beginning with, ``key$=text`` ending with)."""
    if not isinstance(record, dict):
        return False
    for condition in conditions.split(","):
        key, op, want = condition.partition("=")
        if not op:
            raise KeyError(condition)
        test = _FIELD_TESTS.get(key[-1:])
        if test is not None:
            if not test(str(record.get(key[:-1], "")), want):
                return False
        elif str(record.get(key)) != want:
            return False
    return True


def select(data: object, path: str) -> list[object]:
    """Every value ``path`` names (keys joined by ``/``, list indices as integers), with ``*``
    for every key or item of a level, ``(a|b)`` for the keys named and
    ``[key=value,key^=text,key$=text]`` for the records of a list that match."""
    found = [data]
    for key in path.split("/"):
        if key.startswith("[") and key.endswith("]"):
            found = [r for d in found for r in d if _matches(r, key[1:-1])]
        elif key == "*":
            found = [v for d in found for v in (d if isinstance(d, list) else d.values())]
        elif key.startswith("(") and key.endswith(")"):
            found = [_child(d, k) for d in found for k in key[1:-1].split("|")]
        else:
            found = [_child(d, key) for d in found]
    return found


def _as_float(text: str) -> float:
    return float(text.replace(",", "").replace("−", "-"))


def _decimals_unit(text: str) -> float:
    """Half a unit of the last digit shown: the rounding a quoted figure may carry."""
    mantissa, _, exponent = text.replace("−", "-").lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (-decimals + (int(exponent) if exponent else 0))


def agrees(quoted: str, value: float) -> bool:
    """``quoted`` equals ``value`` rounded to the digits ``quoted`` shows."""
    q = _as_float(quoted)
    return abs(q - value) <= _decimals_unit(quoted) * (1 + 1e-9) + 1e-12 * abs(value)


class _Selection(ValueError):
    """A marker's path and its ``min``/``max`` do not go together."""


def _end(values: list[float], end: str | None) -> float:
    """The value a marker names: the only one, or the least/largest with ``min``/``max``."""
    if not values:
        raise _Selection("the path names no value")
    if end is None:
        if len(values) != 1:
            raise _Selection(f"the path names {len(values)} values: add min or max")
        return values[0]
    if len(values) < 2:
        raise _Selection(f"{end} of a path that names {len(values)} value(s)")
    return min(values) if end == "min" else max(values)


def check_text(text: str, doc: str, results: Path = RESULTS) -> list[Figure]:
    """Every marked figure of ``text`` with its JSON value and the problem, if any."""
    cache: dict[str, object] = {}
    figures = []
    for m in MARKER.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        source = f"{m['file']}:{m['path'].strip()}" + (f" {m['end']}" if m["end"] else "")
        before = text[: m.start()]
        start = max(before.rfind("-->"), before.rfind("\n\n"))
        numbers = list(NUMBER.finditer(before, max(start, 0)))
        if not numbers:
            figures.append(Figure(doc, line, "", source, None, "no number before the marker"))
            continue
        quoted = numbers[-1].group()
        try:
            if m["file"] not in cache:
                cache[m["file"]] = json.loads((results / m["file"]).read_text(encoding="utf-8"))
            values = [float(v) for v in select(cache[m["file"]], m["path"].strip())]
            value = _end(values, m["end"]) * (float(m["factor"]) if m["factor"] else 1.0)
        except FileNotFoundError:
            figures.append(
                Figure(doc, line, quoted, source, None, f"no file benchmarks/results/{m['file']}")
            )
            continue
        except _Selection as e:
            figures.append(Figure(doc, line, quoted, source, None, str(e)))
            continue
        except (KeyError, IndexError, ValueError, TypeError, AttributeError):
            figures.append(Figure(doc, line, quoted, source, None, "no numeric value at that path"))
            continue
        problem = None if agrees(quoted, value) else f"quoted {quoted}, the results say {value:.6g}"
        figures.append(Figure(doc, line, quoted, source, value, problem))
    return figures


def check(paths: Iterable[Path] | None = None, results: Path = RESULTS) -> list[Figure]:
    """Every marked figure of README.md and docs/*.md (or ``paths``)."""
    out = []
    for path in paths if paths is not None else documents():
        name = str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)
        out += check_text(path.read_text(encoding="utf-8"), name, results)
    return out


def main() -> int:
    figures = check()
    for f in figures:
        state = "ok" if f.ok else f"DISAGREES: {f.problem}"
        print(f"{f.doc}:{f.line}: {f.quoted} <- {f.source}: {state}")
    bad = [f for f in figures if not f.ok]
    print(f"{len(figures)} marked figures, {len(bad)} disagree")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

"""Uncertainty arithmetic of the V&V 20 budget, in one place.

* :func:`coverage_factor` / :func:`to_standard`: every stated uncertainty is converted to a
  standard one by the coverage factor it declares (attribute ``coverage_factor``, the data
  contract). A file written before that attribute existed may declare an expanded uncertainty in
  its ``long_name``/``comment`` ("expanded uncertainty ... coverage factor k = 2", as
  ``jointwear sim wear`` does): its k is read from there and the basis says so. An ``_u`` that
  declares neither is read as standard (conventions) and the basis says that too; one that calls
  itself expanded without a k is refused.
* :class:`Component` and :func:`combine`: the components of one budget term (``u_num``, ...) are
  added in quadrature with their sources listed. Each component declares which error sources it
  covers; a component whose sources are already counted by an earlier one is listed as *not
  added* (and why), never added twice and never silently dropped.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from jointwear.compare._decide import Uncertainty, unknown
from jointwear.errors import BadInputError

__all__ = ["Component", "combine", "coverage_factor", "to_standard"]

_K_TEXT = re.compile(r"coverage factor\s*(?:k\s*)?=\s*([0-9.]+)", re.IGNORECASE)


def coverage_factor(attrs: Mapping[str, object], what: str) -> tuple[float, str]:
    """The coverage factor an uncertainty variable declares, and how it was read.

    Parameters
    ----------
    attrs : mapping
        The attributes of the ``<name>_u`` variable.
    what : str
        Its name (for messages).

    Returns
    -------
    (float, str)
        ``k`` (1 for a standard uncertainty) and a note for the basis.

    Raises
    ------
    BadInputError
        A ``coverage_factor`` that is not a number > 0, or an uncertainty that calls itself
        expanded without stating its coverage factor.
    """
    if "coverage_factor" in attrs:
        try:
            k = float(np.asarray(attrs["coverage_factor"]).ravel()[0])  # type: ignore[arg-type]
        except (TypeError, ValueError, IndexError):
            k = float("nan")
        if not (math.isfinite(k) and k > 0):
            raise BadInputError(
                f"{what}: coverage_factor {attrs['coverage_factor']!r} is not a number > 0; "
                "set it to 1 for a standard uncertainty or to the k of an expanded one"
            )
        note = "standard" if k == 1 else f"expanded, coverage_factor k = {k:g}: divided by {k:g}"
        return k, note
    text = " ".join(str(attrs.get(key, "")) for key in ("long_name", "comment"))
    if "expanded" in text.lower():
        found = _K_TEXT.search(text)
        if found is None:
            raise BadInputError(
                f"{what} is an expanded uncertainty without its coverage factor; set the "
                "attribute coverage_factor (e.g. 2) so it can be converted to a standard one"
            )
        k = float(found.group(1))
        return k, (
            f"expanded, k = {k:g} declared in its long_name/comment (no coverage_factor "
            f"attribute): divided by {k:g}"
        )
    return 1.0, "no coverage_factor attribute: read as standard (data contract)"


def to_standard(
    values: np.ndarray, attrs: Mapping[str, object], what: str
) -> tuple[np.ndarray, str]:
    """``values`` of an uncertainty variable converted to standard uncertainty, and the note."""
    k, note = coverage_factor(attrs, what)
    return np.asarray(values, dtype=float) / k, note


@dataclass(frozen=True)
class Component:
    """One contribution to a budget term.

    Attributes
    ----------
    value : float or None
        Standard uncertainty [units of the quantity]; None = this source is not assessed.
    source : str
        Where it comes from and how it was computed.
    covers : frozenset of str
        The error sources it accounts for (e.g. ``{"wear-update interval", "cycle-to-cycle
        variability"}``); two components that share one are not both added.
    relative : bool
        True when ``value`` is applied relative to the simulated value (``rel·|S|``): it
        scales with ``S`` (:attr:`jointwear.compare._decide.Uncertainty.relative`).
    """

    value: float | None
    source: str
    covers: frozenset[str]
    relative: bool = False

    @property
    def known(self) -> bool:
        """True when a finite value is available."""
        return self.value is not None and math.isfinite(self.value)


def combine(term: str, components: Iterable[Component], *, missing: str = "") -> Uncertainty:
    """Root-sum-square of the known components whose sources are not already counted.

    Components are taken in the given order (the more complete first); a known component that
    covers a source already counted is listed as not added. Unknown components are listed with
    their reason. With no known component the term is not assessed (``missing`` says why).
    """
    counted: set[str] = set()
    used: list[Component] = []
    lines: list[str] = []
    for c in components:
        if not c.known:
            lines.append(f"not assessed: {c.source}")
            continue
        overlap = counted & c.covers
        if overlap:
            lines.append(
                f"not added ({', '.join(sorted(overlap))} already counted): {c.source} "
                f"= {c.value:.3g}"
            )
            continue
        counted |= c.covers
        used.append(c)
    if not used:
        reasons = [line[len("not assessed: ") :] for line in lines if line.startswith("not ")]
        return unknown("; ".join([*(reasons or []), *([missing] if missing else [])]) or missing)
    var = sum(float(c.value) ** 2 for c in used)
    total = math.sqrt(var)
    share = sum(float(c.value) ** 2 for c in used if c.relative) / var if var > 0 else 0.0
    if len(used) == 1 and not lines:
        return Uncertainty(total, used[0].source, share)
    shown = [f"{c.source} = {c.value:.3g}" for c in used]
    basis = f"{term} = quadrature sum of: " + "; ".join(shown)
    if lines:
        basis += " | " + "; ".join(lines)
    return Uncertainty(total, basis, share)

"""Where each standard uncertainty of the V&V 20 budget comes from, in order of precedence.

``u_num`` (numerical): the quadrature sum of a verification study (``--verification``) and the
simulation's own ``<name>_u`` (converted by its coverage factor), each source counted once
(:func:`jointwear.compare.budget.combine`); without either, a fraction the user states in the
criteria (labelled *user-stated*); else not assessed.

``u_input`` (model inputs): the spread of an ensemble (``--ensemble``) > a fraction the user
states > not assessed.

``u_D`` (measurement): the measurement's own ``<name>_u`` > not assessed.

Nothing unknown is ever replaced by zero.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointwear.compare._decide import Budget, Uncertainty, unknown
from jointwear.compare.budget import Component, combine
from jointwear.compare.criteria import Criteria
from jointwear.compare.ensemble import Ensemble, spread
from jointwear.compare.study import StudyResult, study_component
from jointwear.compare.verification import GCI, LeastSquaresStudy

__all__ = ["Sources", "SIM_U_COVERS"]

#: what the ``<name>_u`` of a ``jointwear sim wear`` run accounts for (its ``accuracy_note``)
SIM_U_COVERS = frozenset({"wear-update interval", "cycle-to-cycle variability"})


@dataclass(frozen=True)
class Sources:
    """The uncertainty information available to one comparison.

    Attributes
    ----------
    criteria : Criteria
        User statements (``*_u_num_rel``, ``*_u_input_rel``).
    ensemble : Ensemble or None
        Ensembles of simulations for u_input.
    gci : mapping
        Quantity name -> :class:`~jointwear.compare.verification.GCI` or
        :class:`~jointwear.compare.verification.LeastSquaresStudy` from 1-D refinement data.
    compared_cycles : float or None
        Wear cycles of the compared simulation.
    field_values : mapping
        Quantity -> per-ensemble per-run values computed from ensemble fields (preferred over
        the ensemble's scalar outputs).
    studies : mapping
        Quantity -> u_num of a ``jointwear sim verify`` study on the measured band
        (:mod:`jointwear.compare.study`).
    """

    criteria: Criteria
    ensemble: Ensemble | None = None
    gci: Mapping[str, GCI | LeastSquaresStudy] = field(default_factory=dict)
    compared_cycles: float | None = None
    field_values: Mapping[str, Sequence[tuple[int, np.ndarray]]] = field(default_factory=dict)
    studies: Mapping[str, StudyResult] = field(default_factory=dict)

    def u_num(
        self,
        quantity: str,
        s: float,
        stated: float | None,
        family: str,
        stated_note: str = "",
    ) -> Uncertainty:
        """Numerical standard uncertainty of a simulated value ``s`` (``family``: wear/motion).

        ``stated`` is the simulation file's own standard uncertainty of the quantity (already
        converted by its coverage factor, ``stated_note`` says how); it covers the wear-update
        interval and the cycle-to-cycle variability only. A verification study adds what it
        covers; a source counted by both is counted once (the study's estimate, by refinement,
        is taken first). A user-stated fraction is used only when no file gives u_num.
        """
        comps: list[Component] = []
        if quantity in self.studies:
            cyc = self.compared_cycles if family == "wear" else None
            comps.append(study_component(self.studies[quantity], s, cyc))
        g = self.gci.get(quantity)
        if g is not None:
            comps.append(self._verification_component(g, s))
        if stated is not None and np.isfinite(stated):
            note = f" ({stated_note})" if stated_note else ""
            what, covers = (
                (": update interval and cycle-to-cycle variability of the wear rate", SIM_U_COVERS)
                if family == "wear"
                else ("", frozenset({"the simulation's own statement"}))
            )
            comps.append(
                Component(float(stated), f"the simulation file's <name>_u{note}{what}", covers)
            )
        if any(c.known for c in comps):
            return combine("u_num", comps)
        rel = getattr(self.criteria, f"{family}_u_num_rel")
        if rel is not None:
            return Uncertainty(
                rel * abs(s), f"user-stated {rel:.3g}·|S| (criteria {family}_u_num_rel)", 1.0
            )
        if comps:
            return combine("u_num", comps)
        if self.gci:
            return unknown(
                f"the verification study has no '{quantity}', the simulation states none "
                f"(<name>_u) and the criteria state no {family}_u_num_rel"
            )
        return unknown(
            "the simulation states none (<name>_u), no verification study was given "
            f"(--verification) and the criteria state no {family}_u_num_rel"
        )

    @staticmethod
    def _verification_component(g: GCI | LeastSquaresStudy, s: float) -> Component:
        covers = frozenset({f"refinement of {g.refined}"} | g.covers)
        if not g.assessed:
            return Component(None, f"verification study: {g.reason}", covers)
        return Component(
            g.u_num_rel * abs(s), "verification: " + g.describe(), covers, relative=True
        )

    def u_input(self, quantity: str, s: float, family: str) -> Uncertainty:
        """Input standard uncertainty of a simulated value ``s``."""
        if self.ensemble is not None:
            found = list(self.field_values.get(quantity, ()))
            have = {i for i, _ in found}
            found += [(i, v) for i, v in self.ensemble.scalar(quantity) if i not in have]
            if found:
                from jointwear.compare.ensemble import not_a_distribution

                for i, _ in found:
                    why = not_a_distribution(self.ensemble.datasets[i], self.ensemble.names[i])
                    if why:
                        return unknown(why)
                cyc = self.compared_cycles if family == "wear" else None
                parts = [
                    (
                        self.ensemble.names[i],
                        values,
                        self.ensemble.cycles(i) if family == "wear" else None,
                    )
                    for i, values in sorted(found, key=lambda t: t[0])
                ]
                return spread(parts, s, compared_cycles=cyc)
        rel = getattr(self.criteria, f"{family}_u_input_rel")
        if rel is not None:
            return Uncertainty(
                rel * abs(s), f"user-stated {rel:.3g}·|S| (criteria {family}_u_input_rel)", 1.0
            )
        if self.ensemble is not None:
            return unknown(
                f"no ensemble given has '{quantity}' (nor a field it can be computed from), and "
                f"the criteria state no {family}_u_input_rel"
            )
        return unknown(
            f"no ensemble of simulations was given (--ensemble) and the criteria state no "
            f"{family}_u_input_rel"
        )

    def budget(
        self,
        quantity: str,
        s: float,
        family: str,
        *,
        sim_u: float | None,
        meas_u: float | None,
        sim_note: str = "",
        meas_note: str = "",
        calibration: Sequence[tuple[float, str]] = (),
    ) -> Budget:
        """The V&V 20 budget of a simulated value ``s``: :meth:`u_num` (the simulation's own
        standard uncertainty ``sim_u``), :meth:`u_input`, :meth:`u_d` (the measurement's
        ``meas_u``, with the instrument's ``calibration`` terms) and the criteria's coverage
        factor."""
        return Budget(
            self.u_num(quantity, s, sim_u, family, sim_note),
            self.u_input(quantity, s, family),
            self.u_d(meas_u, meas_note, calibration),
            self.criteria.k,
        )

    @staticmethod
    def u_d(
        stated: float | None, note: str = "", calibration: Sequence[tuple[float, str]] = ()
    ) -> Uncertainty:
        """Measurement standard uncertainty: the measurement file's own (``note``: how), with
        the user-stated calibration terms ``(u, basis)`` of the instrument added in quadrature.

        A calibration term alone does not make u_D known: it does not cover the measurement's
        noise, form and alignment, which only the file can state.
        """
        if stated is None or not np.isfinite(stated):
            return unknown("the measurement states no uncertainty (<name>_u)")
        own = note or "stated by the measurement file (<name>_u)"
        if not calibration:
            return Uncertainty(float(stated), own)
        comps = [Component(float(stated), own, frozenset({"measurement file"}))]
        comps += [Component(u, basis, frozenset({basis})) for u, basis in calibration]
        return combine("u_D", comps)

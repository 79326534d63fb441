"""Dotted parameter overrides of a wear run: ``"wear.<field>"`` to the wear settings, the rest
to the simulator parameters (what a sensitivity sweep varies), and how the run's provenance
keeps them."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from jointwear.errors import ParameterError
from jointwear.sim.wear._settings import WearSettings

__all__ = ["apply_overrides", "overrides_record"]


def overrides_record(overrides: Mapping[str, Any]) -> str:
    """The run's ``parameter_overrides`` attribute: the overrides as JSON (sorted names)."""
    return json.dumps({k: _provenance_value(v) for k, v in overrides.items()}, sort_keys=True)


def _provenance_value(value: Any) -> Any:
    """An override's value as the provenance record keeps it: a number as float, a string
    (``contact.formulation``) or a boolean as given."""
    if isinstance(value, (str, bool, np.bool_)):
        return value if isinstance(value, str) else bool(value)
    return float(value)


def apply_overrides(
    params: Any, settings: WearSettings, overrides: Mapping[str, float | str] | None
) -> tuple[Any, WearSettings]:
    """Apply dotted overrides: ``"wear.<field>"`` to the settings, the rest to the parameters.

    Parameters
    ----------
    params : SimParameters or None
        Simulator parameters (None: only ``wear.*`` overrides are allowed, e.g. with a
        prescribed contact model).
    settings : WearSettings
        Wear settings.
    overrides : mapping
        ``{"mechanism.joint_offset": 0.0, "joint.thrust_radius": 9.0e-3, "wear.kw": 1e-15}``;
        SI values, as in the parameter file.

    Raises
    ------
    ParameterError
        An unknown name (the message lists the known ones) or an invalid value.
    """
    from jointwear.sim.mechanisms import replace_checked

    if not overrides:
        return params, settings
    wear = {k[5:]: v for k, v in overrides.items() if k.startswith("wear.")}
    sim = {k: v for k, v in overrides.items() if not k.startswith("wear.")}
    if wear:
        names = {f.name for f in dataclasses.fields(WearSettings)}
        unknown = sorted(set(wear) - names)
        if unknown:
            raise ParameterError(
                f"unknown wear setting(s) {', '.join('wear.' + u for u in unknown)}; known: "
                f"{', '.join(sorted(names))}"
            )
        settings = dataclasses.replace(settings, **wear)
    if sim:
        if params is None:
            raise ParameterError(
                f"override(s) {', '.join(sorted(sim))} need the multibody dynamics; a prescribed "
                "contact model takes only wear.* overrides"
            )
        if any("." not in k for k in sim):
            bad = sorted(k for k in sim if "." not in k)
            raise ParameterError(
                f"override(s) {', '.join(bad)} must be dotted names such as "
                "'mechanism.joint_offset' or 'wear.kw'"
            )
        params = replace_checked(params, sim, where="overrides")
    return params, settings

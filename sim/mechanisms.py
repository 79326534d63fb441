"""The mechanisms the simulator knows, in one table, and what each can model.

A mechanism is a ``[mechanism]`` parameter dataclass, a record module (packing its kernel
slots, initial state, angle flags and record variables: :mod:`jointwear.sim._four_bar_record`,
:mod:`jointwear.sim._slider_record`), an equations-of-motion kernel selected by an integer flag
(``IP[MECH]``, :mod:`jointwear.sim.kernels._equations`) and a named parameter set. Every place
that needs to know which mechanism a :class:`~jointwear.sim.SimParameters` describes asks
:func:`mechanism_of`; adding a mechanism is one record module, one kernel branch and one
:func:`register_mechanism` call (docs/development.md, "Adding a mechanism").

Capabilities
------------
Each entry declares what the mechanism can model in a given configuration
(:attr:`Mechanism.capabilities`): ``"spatial"`` when the journal may tilt and slide along its axis
(the four-bar always; the slider-crank with ``planar = false``). A parameter that acts only
through a capability (:data:`PARAMETER_NEEDS`: the joint offset, the tilt spring, the axial play
and the end-face contact) has no effect without it; :func:`check_applicable` refuses such a
parameter when the user *set* it to a value other than the base parameter set's (a default
value written out is harmless), naming it and the setting that would make it apply.

Light module (no numpy): the command line reads it to build its options.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from jointwear.errors import ParameterError
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.parameters import DEFAULT_PARAMETER_SET, MechanismParameters
from jointwear.sim.slider_crank import SliderCrankParameters

__all__ = [
    "Mechanism",
    "MECHANISMS",
    "PARAMETER_NEEDS",
    "register_mechanism",
    "mechanism_of",
    "check_applicable",
    "foreign_keys",
    "replace_checked",
]


@dataclass(frozen=True)
class Mechanism:
    """One mechanism of the simulator.

    Attributes
    ----------
    name : str
        Its key (``mechanism.kind``, ``SimState.mechanism``), e.g. ``"slider_crank"``.
    title : str
        In words, for records and messages (``"slider-crank"``).
    parameters : type
        The ``[mechanism]`` dataclass; :func:`mechanism_of` recognises a mechanism by it.
    parameter_set : str
        Name of its parameter set in :data:`~jointwear.sim.PARAMETER_SETS` (``--base``).
    record : str
        Module with ``pack_mechanism``, ``initial_vector``, ``INITIAL_STEP``, ``ANGLE_FLAGS`` and
        ``variables`` (imported when first used: it needs numpy).
    kernel_flag : int
        ``IP[MECH]``: the branch of the equations-of-motion kernel.
    capabilities : callable
        ``f(params) -> frozenset`` of what it models with these parameters (``"spatial"``).
    enable : mapping
        Capability -> the setting that provides it, for refusals (``"mechanism.planar =
        false"``); a capability missing here cannot be had with this mechanism at all.
    joint : callable
        ``f(params) -> str``: the label of the clearance joint (``"C"``, ``"B"``).
    attrs : callable
        ``f(params) -> dict``: the record's mechanism-specific attributes.
    mode : callable
        ``f(params) -> str``: the configuration that limits its capabilities, for refusals
        (``"with mechanism.planar = true"``; ``""``: none).
    """

    name: str
    title: str
    parameters: type
    parameter_set: str
    record: str
    kernel_flag: int
    capabilities: Callable[[Any], frozenset[str]]
    enable: Mapping[str, str] = field(default_factory=dict)
    joint: Callable[[Any], str] = lambda params: "C"
    attrs: Callable[[Any], dict[str, Any]] = lambda params: {}
    mode: Callable[[Any], str] = lambda params: ""

    def record_module(self) -> Any:
        """The record module (imported on first use)."""
        return importlib.import_module(self.record)


#: The registered mechanisms by name (:func:`register_mechanism`).
MECHANISMS: dict[str, Mechanism] = {}

#: Parameters that act only through a capability: dotted name -> (capability, what it does).
PARAMETER_NEEDS: dict[str, tuple[str, str]] = {
    "mechanism.joint_offset": ("spatial", "moves the joint out of the links' plane, tilting it"),
    "joint.tilt_stiffness": ("spatial", "resists the journal's tilt"),
    "joint.tilt_damping": ("spatial", "damps the journal's tilt"),
    "joint.axial_clearance": ("spatial", "sets the journal's axial play"),
    "joint.thrust_radius": ("spatial", "places the shoulders' contact with the end faces"),
    "contact.axial_stiffness": ("spatial", "sets the end-face contact's stiffness"),
}


def register_mechanism(mechanism: Mechanism) -> Mechanism:
    """Add ``mechanism`` to :data:`MECHANISMS` (refusing a name or dataclass already taken)."""
    for other in MECHANISMS.values():
        if other.name == mechanism.name or other.parameters is mechanism.parameters:
            raise ValueError(
                f"mechanism {mechanism.name!r} ({mechanism.parameters.__name__}) is already "
                f"registered as {other.name!r}"
            )
    MECHANISMS[mechanism.name] = mechanism
    return mechanism


def mechanism_of(params: Any) -> Mechanism:
    """The registered mechanism of a :class:`~jointwear.sim.SimParameters` (by the type of
    its ``mechanism`` table)."""
    kind = type(params.mechanism)
    for m in MECHANISMS.values():
        if kind is m.parameters:
            return m
    raise ParameterError(
        f"the [mechanism] table is a {kind.__name__}, which no registered mechanism uses; "
        f"known: {', '.join(MECHANISMS)}"
    )


def _differs(value: Any, base: Any) -> bool:
    try:
        return bool(float(value) != float(base))
    except (TypeError, ValueError):
        return value != base


def check_applicable(
    params: Any, given: Mapping[str, Any], base: Any, *, where: str = "parameters"
) -> None:
    """Refuse a parameter the chosen mechanism and mode cannot use.

    Parameters
    ----------
    params : SimParameters
        The resolved parameters (their mechanism and mode decide the capabilities).
    given : mapping
        Dotted name -> value of what the user set (TOML tables flattened, overrides).
    base : SimParameters
        The parameters the user's values were applied to (the base set): a value equal to the
        base's is harmless, written out or not.
    where : str
        Names the source in the message.

    Raises
    ------
    ParameterError
        Naming the parameter, why it has no effect and what would make it apply.
    """
    mech = mechanism_of(params)
    caps = mech.capabilities(params)
    for name, value in given.items():
        need = PARAMETER_NEEDS.get(name)
        if need is None or need[0] in caps:
            continue
        table, key = name.split(".", 1)
        if not _differs(value, getattr(getattr(base, table), key)):
            continue
        fix = (
            f"set {mech.enable[need[0]]} to model it, or remove {name}"
            if need[0] in mech.enable
            else f"the {mech.title} cannot model it: remove {name}"
        )
        raise ParameterError(
            f"{where}: {name} = {value!r} has no effect on the {mech.title}"
            f"{(' ' + mech.mode(params)) if mech.mode(params) else ''} (it {need[1]}, which "
            f"needs a {need[0]} joint); {fix}"
        )


def foreign_keys(params: Any, names: list[str]) -> str:
    """A hint for ``[mechanism]`` names that belong to another registered mechanism:
    ``" (mechanism.planar is a slider-crank parameter: --base slider_crank)"`` or ``""``."""
    here = mechanism_of(params)
    hints = []
    for name in names:
        key = name.split(".", 1)[-1]
        owners = [
            m
            for m in MECHANISMS.values()
            if m is not here and key in getattr(m.parameters, "__dataclass_fields__", {})
        ]
        if owners:
            hints.append(
                f"mechanism.{key} is a parameter of the "
                + " and the ".join(f"{m.title} (--base {m.parameter_set})" for m in owners)
            )
    return f" ({'; '.join(hints)})" if hints else ""


def replace_checked(params: Any, changes: Mapping[str, Any], *, where: str = "parameters") -> Any:
    """``replace_nested(params, **changes)`` (dotted names, SI values), refusing a
    ``[mechanism]`` name of another mechanism (naming its ``--base``) and a parameter the
    resulting mechanism and mode cannot use (:func:`check_applicable`)."""
    from jointwear.params import replace_nested

    mech_keys = [k for k in changes if k.startswith("mechanism.")]
    own = getattr(type(params.mechanism), "__dataclass_fields__", {})
    foreign = [k for k in mech_keys if k.split(".", 1)[1] not in own]
    hint = foreign_keys(params, foreign) if foreign else ""
    if hint:
        raise ParameterError(
            f"{where}: unknown parameter(s) {', '.join(foreign)} for the "
            f"{mechanism_of(params).title}{hint}; choose the mechanism with --base"
        )
    new = replace_nested(params, **changes)
    check_applicable(new, changes, params, where=where)
    return new


def _always_spatial(params: Any) -> frozenset[str]:
    return frozenset({"spatial"})


def _slider_capabilities(params: Any) -> frozenset[str]:
    return frozenset() if params.mechanism.planar else frozenset({"spatial"})


register_mechanism(
    Mechanism(
        name="four_bar",
        title="four-bar",
        parameters=MechanismParameters,
        parameter_set=DEFAULT_PARAMETER_SET,
        record="jointwear.sim._four_bar_record",
        kernel_flag=kn.MECH_FOUR_BAR,
        capabilities=_always_spatial,
    )
)
register_mechanism(
    Mechanism(
        name="slider_crank",
        title="slider-crank",
        parameters=SliderCrankParameters,
        parameter_set="slider_crank",
        record="jointwear.sim._slider_record",
        kernel_flag=kn.MECH_SLIDER_CRANK,
        capabilities=_slider_capabilities,
        enable={"spatial": "mechanism.planar = false"},
        joint=lambda p: "B" if p.mechanism.clearance_at == "crank_rod" else "C",
        attrs=lambda p: {
            "clearance_at": p.mechanism.clearance_at,
            "planar": int(p.mechanism.planar),
        },
        mode=lambda p: "with mechanism.planar = true" if p.mechanism.planar else "",
    )
)

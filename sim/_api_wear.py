"""Public names of the wear part of jointwear.sim (Archard wear, cycle updates, wear maps)."""

from jointwear.sim.wear._calibration import (
    KwCalibration,
    Measurement,
    MultiCalibration,
    calibrate_kw,
    calibrate_kw_and_parameter,
    calibrate_kw_multi,
    resimulator,
)
from jointwear.sim.wear._contact import (
    ConstantContact,
    ContactModel,
    CycleWear,
    DynamicContact,
    WinklerContact,
)
from jointwear.sim.wear._loop import (
    DEFAULT_KW,
    KW_RANGE,
    WearRun,
    WearSettings,
    apply_overrides,
    default_snapshots,
    halved_schedule,
    simulate_wear,
)
from jointwear.sim.wearmap import (
    BearingGrid,
    bore_cylindricity,
    bore_radius,
    plot_wear_history,
    plot_wear_map,
    wear_map_dataset,
    worn_volume,
)

__all__ = [
    "DEFAULT_KW",
    "KW_RANGE",
    "WearSettings",
    "WearRun",
    "simulate_wear",
    "apply_overrides",
    "default_snapshots",
    "KwCalibration",
    "calibrate_kw",
    "Measurement",
    "MultiCalibration",
    "calibrate_kw_multi",
    "calibrate_kw_and_parameter",
    "halved_schedule",
    "resimulator",
    "BearingGrid",
    "wear_map_dataset",
    "worn_volume",
    "bore_radius",
    "bore_cylindricity",
    "plot_wear_map",
    "plot_wear_history",
    "CycleWear",
    "ContactModel",
    "ConstantContact",
    "WinklerContact",
    "DynamicContact",
]

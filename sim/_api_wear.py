"""Public names of the wear part of jointwear.sim (Archard wear, cycle updates, wear maps)."""

from jointwear.sim import wearmap
from jointwear.sim.wear import _loop
from jointwear.sim.wear._calibration import (
    KwCalibration,
    Measurement,
    MultiCalibration,
    calibrate_kw,
    calibrate_kw_and_parameter,
    calibrate_kw_multi,
    resimulator,
)
from jointwear.sim.wear._check import check_accuracy
from jointwear.sim.wear._contact import (
    ConstantContact,
    ContactModel,
    CycleWear,
    DynamicContact,
    WinklerContact,
)

# the names of the wear loop and of the wear maps, as those modules list them
from jointwear.sim.wear._loop import *  # noqa: F403
from jointwear.sim.wearmap import *  # noqa: F403

__all__ = [
    "KwCalibration",
    "calibrate_kw",
    "Measurement",
    "MultiCalibration",
    "calibrate_kw_multi",
    "calibrate_kw_and_parameter",
    "check_accuracy",
    "resimulator",
    "CycleWear",
    "ContactModel",
    "ConstantContact",
    "WinklerContact",
    "DynamicContact",
]
__all__ += _loop.__all__
__all__ += wearmap.__all__

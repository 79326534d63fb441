"""Digital image correlation (``jointwear.dic``): 2D subset DIC, stereo DIC, footage tracking."""

import lazy_loader

# The public names: the __all__ of these modules (module -> None) or the names listed. They are
# imported on first use so that the command line starts fast; ``python docs/scripts/lazy_stubs.py``
# writes them into __init__.pyi, which lazy_loader reads.
_EXPORTS = {
    "_api2d": None,
    "_api3d": None,
    "_api_field": None,
    # the camera models alone (datasets.rig), without the footage tracking _api3d gathers
    "calibration._camera": ("Camera", "StereoCalibration"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

"""The 2D subset-DIC engine over the IC-GN kernels: :class:`SubsetCorrelator` and its
parameters, integer-pixel seeds, image sequences, the result Dataset and its quick-look figure.

The modules are private: the public names are re-exported from :mod:`jointwear.dic`; the
names its sibling subpackages use are importable from here (``_EXPORTS``), loaded on first use.
"""

import lazy_loader

_EXPORTS = {
    "_correlator": ("SubsetCorrelator", "check_image", "check_pair"),
    "_files": ("read_points_file",),
    "_params": ("CorrelationParams", "check_image_origin"),
    "_sequence": ("read_frames", "read_image"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

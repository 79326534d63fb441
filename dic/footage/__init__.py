"""Footage tracking: rig videos and image sequences, body regions (TOML), SIFT
correspondence, frame-to-frame subset tracking, rigid-body fits, the motion Dataset and its
figure.

The modules are private: the public names are re-exported from :mod:`jointwear.dic`; the
names its sibling subpackages use are importable from here (``_EXPORTS``), loaded on first use.
"""

import lazy_loader

_EXPORTS = {
    "_video": ("open_frames", "is_image_sequence", "list_image_sequence", "check_frame_names"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

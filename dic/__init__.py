"""Digital image correlation (``jointwear.dic``): 2D subset DIC, stereo DIC, footage tracking."""

from jointwear._lazy import lazy_api

# Public names come from the modules below; they are imported on first use (PEP 562) so that
# the command line starts fast.
__getattr__, __dir__ = lazy_api(
    __name__, ["jointwear.dic._api2d", "jointwear.dic._api3d", "jointwear.dic._api_field"]
)

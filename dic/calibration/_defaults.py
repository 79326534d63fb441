"""Defaults of the stereo calibration, one source for the library and ``jointwear dic
calibrate`` (light: the CLI reads them without importing the numerical stack)."""

#: fewest usable board views
MIN_VIEWS = 6
#: largest acceptable stereo reprojection RMS [pixel]
MAX_RMS_PX = 1.0
#: views above this per-camera reprojection RMS [pixel] are dropped
MAX_VIEW_RMS_PX = 1.0
#: videos: use every N-th frame
VIDEO_EVERY = 10
#: ArUco dictionary of a ChArUco board
CHARUCO_DICTIONARY = "DICT_5X5_100"
#: board kind and its squares along x and y (not inner corners)
BOARD_KIND = "chessboard"
BOARD_SQUARES = (10, 7)

"""The numba kernels the command line calls from Python, with their argument types: what the
compile-once warm-up (:mod:`jointwear._compile`) compiles. Written by
``docs/scripts/kernel_manifest.py`` (do not edit by hand); ``cpu_s`` is the CPU time each
compilation took when it was recorded (2026-11-29), the warm-up's estimate of what is left.
"""

#: (module, function, argument types as numba writes them, CPU seconds when recorded)
KERNELS: tuple[tuple[str, str, str, float], ...] = (
    (
        "jointwear.datasets.speckle",
        "_render_kernel",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), float64, float64, float64, int64, int64, float64, float64)",
        0.6,
    ),
    (
        "jointwear.dic.calibration._camera",
        "_undistort_impl",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), int64, Array(float64, 2, 'C', False, aligned=True))",
        0.4,
    ),
    (
        "jointwear.dic.calibration._stereo",
        "_refine_points_impl",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), int64, Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True))",
        5.1,
    ),
    (
        "jointwear.dic.field._strain",
        "_strain_kernel",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), float64, Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), int64, Array(float64, 3, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(int8, 2, 'C', False, aligned=True))",
        3.1,
    ),
    (
        "jointwear.dic.footage._rigid",
        "_robust_rigid_impl",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True), float64, int64, int64, Array(float64, 3, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True), float64, Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True))",
        8.2,
    ),
    (
        "jointwear.dic.icgn._drive",
        "affine_references",
        "(Tuple((Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((int64, bool, int64, float64, float64, float64, float64, float64, int64)), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True))",
        3.6,
    ),
    (
        "jointwear.dic.icgn._drive",
        "icgn_affine_loaded",
        "(Tuple((Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True))), Tuple((Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((int64, bool, int64, float64, float64, float64, float64, float64, int64)), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True), Tuple((Array(float64, 1, 'C', False, aligned=True), Array(int32, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))))",
        7.1,
    ),
    (
        "jointwear.dic.icgn._drive",
        "icgn_many",
        "(Tuple((Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((int64, bool, int64, float64, float64, float64, float64, float64, int64)), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True), Tuple((Array(float64, 1, 'C', False, aligned=True), Array(int32, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))))",
        4.8,
    ),
    (
        "jointwear.dic.icgn._drive",
        "icgn_serial",
        "(Tuple((Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((int64, bool, int64, float64, float64, float64, float64, float64, int64)), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(bool, 1, 'C', False, aligned=True), Tuple((Array(float64, 1, 'C', False, aligned=True), Array(int32, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))))",
        8.3,
    ),
    (
        "jointwear.dic.icgn._drive",
        "rg_propagate",
        "(int64, Array(int64, 1, 'C', False, aligned=True), Tuple((Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True))), Tuple((int64, bool, int64, float64, float64, float64, float64, float64, int64)), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Tuple((Array(float64, 1, 'C', False, aligned=True), Array(int32, 1, 'C', False, aligned=True), Array(int8, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))), Array(bool, 1, 'C', False, aligned=True), int64)",
        9.9,
    ),
    (
        "jointwear.dic.icgn._interp",
        "_central_gradients",
        "(Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))",
        0.3,
    ),
    (
        "jointwear.dic.icgn._interp",
        "_prefilter_2d",
        "(Array(float64, 2, 'C', False, aligned=True), int64, Array(float64, 2, 'C', False, aligned=True))",
        2.8,
    ),
    (
        "jointwear.dic.icgn._interp",
        "_prefilter_spans",
        "(Array(float32, 2, 'C', False, aligned=True), int64, int64, int64, int64, int64, Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), int64, int64, float64, Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True))",
        1.9,
    ),
    (
        "jointwear.dic.icgn._interp",
        "_prefilter_spans",
        "(Array(uint8, 2, 'C', False, aligned=True), int64, int64, int64, int64, int64, Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), int64, int64, float64, Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True))",
        1.2,
    ),
    (
        "jointwear.dic.icgn._interp",
        "_reset_spans",
        "(Array(float64, 2, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True))",
        0.6,
    ),
    (
        "jointwear.dic.icgn._reference",
        "subset_kappa",
        "(Array(float64, 2, 'C', False, aligned=True), int64, Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), int64, Array(float64, 1, 'C', False, aligned=True))",
        3.1,
    ),
    (
        "jointwear.dic.icgn._reference",
        "subset_std",
        "(Array(float64, 2, 'C', False, aligned=True), Array(int64, 2, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), int64, int64)",
        0.8,
    ),
    (
        "jointwear.sim.kernels._integrator",
        "integrate",
        "(float64, Array(float64, 1, 'C', False, aligned=True), float64, float64, Tuple((Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True))), int64, Tuple((Array(float64, 1, 'C', False, aligned=True), Array(int64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 2, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True), Array(float64, 3, 'C', False, aligned=True), Array(float64, 1, 'C', False, aligned=True))), Tuple((Array(int64, 1, 'C', False, aligned=True), float64, float64, float64, float64, float64, float64)))",
        19.7,
    ),
)

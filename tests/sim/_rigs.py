"""Rigs the wear tests share (with benchmarks/bench_sim_rigs.py)."""

#: The six rigs off the study's default of issue 16, each changing one parameter (dotted name
#: -> value): with the old wear controller each of them stalled with dN collapsing to 1-2
#: cycles. tests/sim/test_wear_rigs.py runs them at reduced size, the benchmark at full size.
OFF_DEFAULT_RIGS = {
    "bearing_radius_8.5mm": {"joint.bearing_radius": 8.5e-3},
    "crank_60rpm": {"mechanism.crank_speed_rpm": 60.0},
    "crank_240rpm": {"mechanism.crank_speed_rpm": 240.0},
    "friction_0": {"friction.static_coefficient": 0.0, "friction.dynamic_coefficient": 0.0},
    "axial_clearance_2mm": {"joint.axial_clearance": 2e-3},
    "joint_offset_0": {"mechanism.joint_offset": 0.0},
}

#: Parameter-file tables of a coarse joint (6 x 60) with wear settings whose accuracy the wear
#: rate's cycle-to-cycle variability keeps out of reach (tol 0.05 at dN 50, kw x 100): quick
#: runs that end "accuracy not reached" with a warning. Ends inside [wear]: append settings.
NOISE_LIMITED_TOML = (
    "[joint]\nn_layers = 6\nn_points = 60\n\n[wear]\nkw = 9.0e-14\ntol = 0.05\ndn = 50\n"
)

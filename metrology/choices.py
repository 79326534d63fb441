"""The choices and defaults of the metrology options, in one place.

The library checks its keywords against these and the command line offers them as its
choices and shows the defaults in its help (``metrology/_cli_options.py``). This module imports
nothing heavy, so that ``jointwear --help`` stays fast.
"""

from __future__ import annotations

__all__ = [
    "ANGLE_UNITS",
    "ARCS",
    "VALUE_KINDS",
    "LAYOUTS",
    "Z_SOURCES",
    "PRESETS",
    "READERS",
    "REFERENCES",
    "PLAUSIBILITY",
    "WEAR_SHAPES",
    "WEAR_SHAPE",
    "UNWORN_THRESHOLD",
]

#: Units an angle column may have (``index`` = sample number over one full turn).
ANGLE_UNITS = ("deg", "rad", "index", "grad")
#: Angular spans a layer may have.
ARCS = ("full", "partial")
#: Meanings of a value column.
VALUE_KINDS = ("radius", "deviation")
#: Values of ``layout`` of :func:`~jointwear.metrology.read_scan`.
LAYOUTS = ("auto", "single", "folder", "long", "wide", "blocks")
#: Values of ``z_source`` of :func:`~jointwear.metrology.read_scan`.
Z_SOURCES = ("auto", "option", "column", "numbers", "manifest", "header", "names", "spacing")
#: The reader of each preset: name -> ("module:function", what it reads). One module per
#: instrument family under ``metrology/readers/``, registered here and nowhere else (the
#: command line offers these names; :func:`~jointwear.metrology.readers.registry.reader_for`
#: imports the function when it is used; docs/development.md, "Adding a reader").
READERS: dict[str, tuple[str, str]] = {
    "generic": (
        "jointwear.metrology.readers.scan:read_scan",
        "every format choice sniffed from the file or given",
    ),
    "talyrond": (
        "jointwear.metrology.readers.talyrond:read_talyrond",
        "Taylor Hobson Talyrond: values in µm unless stated, whole revolutions",
    ),
}
#: Reader presets (the names of :data:`READERS`).
PRESETS = tuple(READERS)

#: Reference names accepted (short form -> ISO circle / cylinder names).
REFERENCES: dict[str, tuple[str, str]] = {
    "LS": ("LSCI", "LSCY"),
    "MZ": ("MZCI", "MZCY"),
    "MI": ("MICI", "MICY"),
    "MC": ("MCCI", "MCCY"),
}

#: Plausibility limits of the header cross-checks (override with the same-named options).
PLAUSIBILITY: dict[str, float] = {
    "radius_min": 0.5e-3,  # [m] smallest bore/shaft radius a roundness instrument measures here
    "radius_max": 2.0,  # [m] largest
    "max_deviation": 1e-3,  # [m] largest |radial deviation| (a roundness gauge's range)
    "min_form": 10e-9,  # [m] smallest peak-to-valley of a deviation trace (below any probe noise)
    "nominal_tolerance": 0.05,  # relative: measured radius within 5 % of the stated nominal
    "deviation_fraction": 0.05,  # |deviation| at most 5 % of the stated nominal radius
    "max_missing": 0.05,  # share of a layer's points that may be missing (NaN)
    "form_fraction": 0.01,  # deviation peak-to-valley (0.5-99.5 %) at most 1 % of the radius
    "spacing_tolerance": 0.01,  # relative: stated layer spacing vs the layers found
    "points_tolerance": 0.01,  # relative: stated angular step vs the step of the angles
    "filter_energy": 1e-4,  # energy above 3 k_c / energy of harmonics >= 2 (a Gaussian k_c
    # filter leaves 2^-18 = 3.8e-6 of what was there), beyond the export's rounding floor
}

#: Unworn reference shapes of :func:`~jointwear.metrology.wear_map`, and its default.
WEAR_SHAPES = ("auto", "cylinder", "circle", "form")
WEAR_SHAPE = "auto"
#: Unworn points of a wear map lie within this many robust standard deviations [1].
UNWORN_THRESHOLD = 3.0

"""``jointwear sim wear``: long wear runs with progress, checkpoints and resume."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import typer

from jointwear._cli import Overwrite
from jointwear.sim._cli_options import Base, Progress, WearParams
from jointwear.sim._defaults import BORE_LAYERS, BORE_POINTS, DEFAULT_PARAMETER_SET
from jointwear.sim.wear._settings import CALIBRATION_RTOL, DEFAULT_CYCLES, WearSettings

__all__ = ["register"]


def _parse_snapshots(text: str | None) -> list[float] | None:
    from jointwear.errors import BadInputError

    if text is None or not text.strip():
        return None
    try:
        return [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise BadInputError(
            f"--snapshots {text!r}: expected comma-separated cycle counts, e.g. 1e4,1e5,4e5,1e6"
        ) from None


def _measurements(given: dict[str, list[str] | None], default_cycles: float) -> list[Any]:
    """Measurements from ``value`` or ``value@cycles`` strings (µm, or mm³ for the volume)."""
    from jointwear.errors import BadInputError
    from jointwear.sim.wear._calibration import Measurement

    flags = {
        "max_depth": "--max-depth-um",
        "volume": "--volume-mm3",
        "cylindricity": "--cylindricity-um",
    }
    out = []
    for quantity, texts in given.items():
        scale = 1e-9 if quantity == "volume" else 1e-6
        for text in texts or []:
            value, _, at = text.partition("@")
            try:
                v = float(value) * scale
                c = float(at) if at else default_cycles
            except ValueError:
                raise BadInputError(
                    f"{flags[quantity]} {text!r}: expected a number, optionally @cycles, "
                    "e.g. 28.32@4e5"
                ) from None
            out.append(Measurement(quantity, c, v))
    return out


def _parse_vary(text: str) -> tuple[str, tuple[float, float]]:
    from jointwear.errors import BadInputError

    name, _, rng = text.partition("=")
    lo, _, hi = rng.partition(":")
    try:
        bounds = (float(lo), float(hi))
    except ValueError:
        raise BadInputError(
            f"--vary {text!r}: expected NAME=LO:HI, e.g. mechanism.joint_offset=0:0.02"
        ) from None
    if not name.strip() or "." not in name:
        raise BadInputError(f"--vary {text!r}: NAME must be a dotted parameter name")
    return name.strip(), bounds


def _check_kinds(given: list[str] | None) -> tuple[str, ...]:
    """The accuracy checks asked for (``--check interval --check grid`` or comma-separated)."""
    from jointwear.errors import BadInputError
    from jointwear.sim.wear._check import CHECK_KINDS

    kinds = tuple(dict.fromkeys(k.strip() for v in (given or []) for k in v.split(",") if k))
    bad = [k for k in kinds if k not in CHECK_KINDS]
    if bad:
        raise BadInputError(
            f"--check {', '.join(bad)}: unknown check; choose from {', '.join(CHECK_KINDS)}"
        )
    return kinds


def _progress_text(info: dict[str, Any]) -> str:
    """The progress bar's description after an update."""
    return f"wear: dN={info['dn']:d} max depth={info['max_depth'] * 1e6:.2f} µm" + (
        "" if info["accepted"] else " (rejected, retrying)"
    )


def _write_figure(ds: Any, figure: Path) -> None:
    """The final wear map (depth map and profile), in the format the file name says."""
    import matplotlib

    matplotlib.use("Agg")
    from jointwear import io
    from jointwear.sim.wearmap import plot_wear_map

    io.save_figure(plot_wear_map(ds, kind="both"), figure, dpi=110, what="--figure")


def _summary(out: Path, ds: Any, run: Any) -> str:
    """The closing line: cycles, max depth and worn volume with their uncertainty, accuracy."""
    u_max = float(ds["max_wear_depth_u"][-1])
    u_vol = float(ds["worn_volume_u"][-1])
    pm = (lambda u, f: f" ± {u * f:.2g}") if u_max == u_max else (lambda u, f: "")
    return (
        f"{out}: {run.cycles_done} cycles, max depth "
        f"{float(ds['max_wear_depth'][-1]) * 1e6:.2f}{pm(u_max, 1e6)} µm, worn volume "
        f"{float(ds['worn_volume'][-1]) * 1e9:.4g}{pm(u_vol, 1e9)} mm³ "
        f"(accuracy {ds.attrs['accuracy_status']}, k = 2), {ds.attrs['n_updates']} updates, "
        f"{run.cycles_simulated:g} cycles simulated"
    )


def calibrate(
    simulated: Annotated[Path, typer.Argument(help="Wear map written by 'jointwear sim wear'.")],
    max_depth_um: Annotated[
        list[str] | None,
        typer.Option(
            "--max-depth-um",
            help="Measured maximum wear depth \\[µm], optionally @cycles (e.g. 35@1.2e6); "
            "repeat for several snapshots.",
        ),
    ] = None,
    volume_mm3: Annotated[
        list[str] | None,
        typer.Option(
            "--volume-mm3", help="Measured worn volume \\[mm³], optionally @cycles; repeatable."
        ),
    ] = None,
    cylindricity_um: Annotated[
        list[str] | None,
        typer.Option(
            "--cylindricity-um",
            help="Measured growth of the bore's cylindricity \\[µm], optionally @cycles "
            "(e.g. 28.32@4e5); repeatable.",
        ),
    ] = None,
    measured_map: Annotated[
        Path | None,
        typer.Option("--map", help="Measured wear map (netCDF with wear_depth(z, theta))."),
    ] = None,
    cycles: Annotated[
        float | None,
        typer.Option(
            "--cycles",
            help="Cycle count of a measurement given without @cycles (default: last).",
        ),
    ] = None,
    vary: Annotated[
        str | None,
        typer.Option(
            "--vary",
            help="Also fit one simulator parameter within bounds, NAME=LO:HI in SI units "
            "(e.g. mechanism.joint_offset=0:0.02 \\[m]); needs two or more snapshots.",
        ),
    ] = None,
    resimulate: Annotated[
        bool,
        typer.Option(
            "--resimulate/--linear",
            help="Check the linear estimate by re-simulating (default) or stop at it.",
        ),
    ] = True,
    rtol: Annotated[
        float, typer.Option("--rtol", help="Relative tolerance of the re-simulated match.")
    ] = CALIBRATION_RTOL,
) -> None:
    """Estimate the wear coefficient kw from measured wear depth, volume, cylindricity or a map.

    Several snapshots (repeat an option, each value@cycles) are fitted together by least
    squares of the log misfit; each residual and a leave-one-out check are printed.
    """
    from jointwear import io
    from jointwear.errors import BadInputError
    from jointwear.sim.wear._calibration import calibration_report, check_wear_run

    sim = io.load(simulated)
    check_wear_run(sim, f"SIMULATED '{simulated}'")
    last = float(sim["cycles"].values[-1])
    meas = _measurements(
        {"max_depth": max_depth_um, "volume": volume_mm3, "cylindricity": cylindricity_um},
        cycles if cycles is not None else last,
    )
    n_given = len(meas) + (measured_map is not None)
    if n_given == 0 or (measured_map is not None and meas):
        raise BadInputError(
            "give one measurement, or several scalar snapshots: --max-depth-um, --volume-mm3, "
            f"--cylindricity-um (repeatable, value@cycles) or --map alone (got {n_given})"
        )
    plain = all(
        "@" not in v for v in (max_depth_um or []) + (volume_mm3 or []) + (cylindricity_um or [])
    )
    lines = calibration_report(
        sim,
        meas,
        measured_map=io.load(measured_map) if measured_map is not None else None,
        single=plain,
        cycles=cycles,
        vary=_parse_vary(vary) if vary is not None else None,
        resimulate=resimulate,
        rtol=rtol,
    )
    for line in lines:
        typer.echo(line)


# options of ``sim wear`` (the update settings show the library's defaults)
_Cycles = Annotated[float, typer.Option("--cycles", help="Target number of cycles.")]
_Resume = Annotated[
    bool, typer.Option("--resume", help="Continue from the checkpoint of an earlier run.")
]
_Checkpoint = Annotated[
    Path | None, typer.Option("--checkpoint", help="Checkpoint file (default: <out>.ckpt).")
]
_Snapshots = Annotated[
    str | None,
    typer.Option(
        "--snapshots",
        help="Cycle counts to store, comma-separated (default 1-2-5 steps and the target).",
    ),
]


def _default(field: str) -> str:
    """The library's default of ``WearSettings.<field>``, as the help shows it (the option
    overrides the ``[wear]`` table's value, which overrides this one)."""
    value = getattr(WearSettings, field)
    return f"{value:g}" if isinstance(value, float) else str(value)


_Kw = Annotated[
    float | None,
    typer.Option(
        "--kw", help=f"Archard wear coefficient \\[m²/N = m³/(N m)]; default {_default('kw')}."
    ),
]
_Scheme = Annotated[
    Literal["adaptive", "fixed", "schedule"] | None,
    typer.Option(
        "--scheme",
        help="Update interval: adaptive, fixed, or schedule (intervals from the \\[wear] table); "
        f"default {_default('scheme')}.",
    ),
]
_Dn = Annotated[
    int | None,
    typer.Option(
        "--dn",
        help=f"Cycles per update (fixed) or first interval (adaptive); default {_default('dn')}.",
    ),
]
_Tol = Annotated[
    float | None,
    typer.Option(
        "--tol",
        help="Adaptive: allowed relative change of the wear-rate field; "
        f"default {_default('tol')}.",
    ),
]
_Settle = Annotated[
    float | None,
    typer.Option(
        "--settle",
        help="Cycles discarded after each update before accumulating; "
        f"default {_default('settle_cycles')}.",
    ),
]
_Layers = Annotated[
    int | None,
    typer.Option("--layers", help=f"Layers over the bearing width (Nl); default {BORE_LAYERS}."),
]
_Points = Annotated[
    int | None,
    typer.Option("--points", help=f"Points per layer (Nd); default {BORE_POINTS}."),
]
_Contact = Annotated[
    Literal["dynamics", "winkler"],
    typer.Option(
        "--contact",
        help="dynamics (the multibody simulation) or winkler (prescribed load, for tests).",
    ),
]
_Figure = Annotated[
    Path | None,
    typer.Option(
        "--figure", help="Also write a figure of the final wear map (PNG, PDF, SVG by its suffix)."
    ),
]
_Check = Annotated[
    list[str] | None,
    typer.Option(
        "--check",
        help="After the run, repeat it with 'interval' (every update interval halved) or "
        "'grid' (spacing halved) and compare with the stated accuracy; repeatable. Exit 1 "
        "if a change exceeds it.",
    ),
]


def wear(
    out: Annotated[Path, typer.Option("--out", help="Output wear map (netCDF).")],
    overwrite: Overwrite = False,
    cycles: _Cycles = DEFAULT_CYCLES,
    kw: _Kw = None,
    params: WearParams = None,
    base: Base = DEFAULT_PARAMETER_SET,
    resume: _Resume = False,
    checkpoint: _Checkpoint = None,
    snapshots: _Snapshots = None,
    scheme: _Scheme = None,
    dn: _Dn = None,
    tol: _Tol = None,
    settle: _Settle = None,
    layers: _Layers = None,
    points: _Points = None,
    contact: _Contact = "dynamics",
    figure: _Figure = None,
    progress: Progress = None,
    check: _Check = None,
) -> None:
    """Simulate Archard wear of joint C over many cycles; checkpoint after every update."""
    import logging

    from jointwear import io
    from jointwear.progress import progress_bar
    from jointwear.sim.wear._files import simulate_wear_to_file

    # the accuracy warning is printed below with the result; without this handler Python's
    # last-resort handler would print it a second time
    logging.getLogger("jointwear.sim.wear").addHandler(logging.NullHandler())
    io.check_writable(out, what="--out")
    if figure is not None:
        io.check_writable(figure, what="--figure")
        io.figure_format(figure, what="--figure")
    snaps = _parse_snapshots(snapshots)
    kinds = _check_kinds(check)
    overrides = {"kw": kw, "scheme": scheme, "dn": dn, "tol": tol, "settle_cycles": settle}
    with progress_bar("wear", total=float(cycles), enabled=progress) as bar:
        task = bar.tasks[0].id
        ds, run = simulate_wear_to_file(
            out,
            params,
            overrides=overrides,
            contact=contact,
            layers=layers,
            points=points,
            base=base,
            cycles=cycles,
            snapshots=snaps,
            checkpoint=checkpoint,
            resume=resume,
            overwrite=overwrite,
            on_start=lambda run: bar.update(task, completed=run.cycles_done),
            on_update=lambda info: bar.update(
                task, completed=info["cycles_done"], description=_progress_text(info)
            ),
            warn=lambda message: typer.echo(message, err=True),
            checks=kinds,
        )
    if figure is not None:
        _write_figure(ds, figure)
    for key in ("convergence_warning", "accuracy_warning", "contact_validity_warning"):
        if key in ds.attrs:
            typer.echo(f"warning: {ds.attrs[key]}", err=True)
    typer.echo(_summary(out, ds, run))
    if ds.attrs.get("accuracy_check_status") == "inconsistent":
        from jointwear.errors import ValidationFailed

        raise ValidationFailed(
            f"{out}: the accuracy check found a change larger than the stated accuracy "
            "(attribute accuracy_check_status); the run's *_u do not cover its numerical "
            "error - use a smaller tol or a finer grid"
        )


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim wear`` and ``jointwear sim calibrate-kw`` to the ``sim`` group."""
    app.command("calibrate-kw")(calibrate)
    app.command("wear")(wear)

"""``jointwear sim wear``: long wear runs with progress, checkpoints and resume."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import typer

from jointwear._cli import Overwrite
from jointwear._version import source_attribute
from jointwear.sim.parameters import DEFAULT_PARAMETER_SET
from jointwear.sim.wear._settings import DEFAULT_KW

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


def _load_settings(params_file: Path | None, overrides: dict[str, Any]) -> tuple[Any, dict]:
    """WearSettings from the [wear] table of the TOML file plus command-line overrides;
    also returns the rest of the TOML (the simulator's parameters)."""
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim.wear._settings import WearSettings

    table: dict[str, Any] = read_toml(params_file) if params_file is not None else {}
    wear = dict(table.pop("wear", {}) or {})
    wear.update({k: v for k, v in overrides.items() if v is not None})
    return from_mapping(WearSettings, wear, where="wear"), table


def _sim_parameters(
    params_file: Path | None,
    rest: dict[str, Any],
    grid: tuple,
    base: str = DEFAULT_PARAMETER_SET,
) -> Any:
    """The simulator's parameters: the named set, updated from the TOML file and grid options."""
    from jointwear.errors import BadInputError
    from jointwear.sim.parameters import PARAMETER_SETS, parameters_from_tables

    try:
        if params_file is not None and rest:  # the TOML file is read once, by _load_settings
            params = parameters_from_tables(rest, base, where=f"parameter file '{params_file}'")
        else:
            params = PARAMETER_SETS[base]
    except KeyError as exc:
        raise BadInputError(f"--base: {exc.args[0]}") from None
    layers, points = grid
    changes = {}
    if layers is not None:
        changes["joint.n_layers"] = layers
    if points is not None:
        changes["joint.n_points"] = points
    if changes:
        from jointwear.params import replace_nested

        params = replace_nested(params, **changes)
    return params


def _resumable(exc: Exception, cycles_done: float, ckpt: Path) -> Exception:
    """A failed write of a wear run (full disk) that says how to continue it."""
    from jointwear.outputs import OutputError

    return OutputError(
        f"{exc}. The wear run stopped after {cycles_done:g} cycles; nothing computed is lost "
        f"beyond the last update: its checkpoint '{ckpt}' holds the last good state. Free space "
        "and run the same command again with --resume to continue it."
    )


def demo_winkler_contact(grid: Any) -> Any:
    """The prescribed contact of ``--contact winkler``: a 20 N load on a Winkler lining whose
    direction swings sinusoidally between 45 and 135 degrees over the cycle, slightly tilted."""
    import numpy as np

    from jointwear.sim.wear._contact import WinklerContact

    n = 24
    t = (np.arange(n) + 0.5) / n
    return WinklerContact(
        grid,
        load=20.0,
        load_angle_deg=tuple(90.0 + 45.0 * np.sin(2 * np.pi * t)),
        foundation_modulus=1e11,
        sliding=0.02,
        tilt=2e-3,
        n_steps=n,
    )


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim wear`` and ``jointwear sim calibrate-kw`` to the ``sim`` group."""

    @app.command("calibrate-kw")
    def calibrate(
        simulated: Annotated[
            Path, typer.Argument(help="Wear map written by 'jointwear sim wear'.")
        ],
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
        ] = 0.02,
    ) -> None:
        """Estimate the wear coefficient kw from measured wear depth, volume, cylindricity or a map.

        Several snapshots (repeat an option, each value@cycles) are fitted together by least
        squares of the log misfit; each residual and a leave-one-out check are printed.
        """
        from jointwear import io
        from jointwear.errors import BadInputError
        from jointwear.sim.wear._calibration import calibrate_kw, resimulator

        sim = io.load(simulated)
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
            "@" not in v
            for v in (max_depth_um or []) + (volume_mm3 or []) + (cylindricity_um or [])
        )
        if vary is None and (measured_map is not None or (len(meas) == 1 and plain)):
            if measured_map is not None:
                quantity, measured = "map", io.load(measured_map)
            else:
                quantity, measured = meas[0].quantity, meas[0].value
            cal = calibrate_kw(
                sim,
                measured,
                quantity=quantity,
                cycles=cycles,
                resimulate=resimulator(sim) if resimulate else None,
                rtol=rtol,
            )
            what = "measured map" if quantity == "map" else meas[0].describe()
            typer.echo(f"data used: {what} (at {cal.cycles:.6g} cycles)")
            typer.echo(f"kw (linear estimate): {cal.kw_linear:.4g} m²/N")
            if cal.linearity_error is not None:
                typer.echo(
                    f"re-simulated with it: {100 * cal.linearity_error:+.1f} % off the measurement "
                    "(wear is not exactly linear in kw)"
                )
                state = "converged" if cal.converged else "NOT converged"
                typer.echo(
                    f"kw (calibrated, {state} after {len(cal.iterations) - 1} re-simulations): "
                    f"{cal.kw:.4g} m²/N"
                )
                typer.echo(
                    f"residual of the last re-simulation: "
                    f"{100 * (cal.iterations[-1][1] / cal.measured - 1):+.1f} %"
                )
            return
        from jointwear.sim.wear._calibration import calibrate_kw_and_parameter, calibrate_kw_multi

        two_sim = None
        if vary is not None:
            name, bounds = _parse_vary(vary)
            if not resimulate:
                raise BadInputError("--vary needs re-simulation; drop --linear")
            if len(meas) < 2:
                raise BadInputError("--vary needs at least two measured snapshots")
            two_sim = resimulator(sim, name)
        one = calibrate_kw_multi(
            sim, meas, resimulate=resimulator(sim) if resimulate else None, rtol=rtol / 4
        )
        typer.echo("kw alone:")
        for line in one.report():
            typer.echo(f"  {line}")
        if two_sim is not None:
            two = calibrate_kw_and_parameter(
                two_sim, meas, parameter=name, bounds=bounds, kw0=one.kw
            )
            typer.echo(f"kw and {name}:")
            for line in two.report():
                typer.echo(f"  {line}")
            better = two.rms_log_misfit < 0.5 * one.rms_log_misfit
            typer.echo(
                f"two parameters {'fit clearly better than' if better else 'do not fit clearly better than'} "
                f"kw alone (RMS log misfit {100 * two.rms_log_misfit:.1f} % vs "
                f"{100 * one.rms_log_misfit:.1f} %)"
            )
        typer.echo(f"kw (calibrated): {one.kw:.4g} m²/N")

    @app.command("wear")
    def wear(
        out: Annotated[Path, typer.Option("--out", help="Output wear map (netCDF).")],
        overwrite: Overwrite = False,
        cycles: Annotated[float, typer.Option("--cycles", help="Target number of cycles.")] = 1e6,
        kw: Annotated[
            float | None,
            typer.Option(
                "--kw",
                help=f"Archard wear coefficient \\[m²/N = m³/(N m)]; default {DEFAULT_KW:g}.",
            ),
        ] = None,
        params: Annotated[
            Path | None,
            typer.Option(
                "--params",
                help="TOML file: simulator parameters, and a \\[wear] table (kw, scheme, dn, tol, ...).",
            ),
        ] = None,
        base: Annotated[
            str,
            typer.Option(
                "--base",
                help="Named parameter set the --params overrides apply to: the four-bar's "
                f"{DEFAULT_PARAMETER_SET} or slider_crank.",
            ),
        ] = DEFAULT_PARAMETER_SET,
        resume: Annotated[
            bool, typer.Option("--resume", help="Continue from the checkpoint of an earlier run.")
        ] = False,
        checkpoint: Annotated[
            Path | None,
            typer.Option("--checkpoint", help="Checkpoint file (default: <out>.ckpt)."),
        ] = None,
        snapshots: Annotated[
            str | None,
            typer.Option(
                "--snapshots",
                help="Cycle counts to store, comma-separated (default 1-2-5 steps and the target).",
            ),
        ] = None,
        scheme: Annotated[
            Literal["adaptive", "fixed", "schedule"] | None,
            typer.Option(
                "--scheme",
                help="Update interval: adaptive, fixed, or schedule (intervals from the \\[wear] table).",
            ),
        ] = None,
        dn: Annotated[
            int | None,
            typer.Option("--dn", help="Cycles per update (fixed) or first interval (adaptive)."),
        ] = None,
        tol: Annotated[
            float | None,
            typer.Option("--tol", help="Adaptive: allowed relative change of the wear-rate field."),
        ] = None,
        settle: Annotated[
            float | None,
            typer.Option(
                "--settle", help="Cycles discarded after each update before accumulating."
            ),
        ] = None,
        layers: Annotated[
            int | None, typer.Option("--layers", help="Layers over the bearing width (Nl).")
        ] = None,
        points: Annotated[
            int | None, typer.Option("--points", help="Points per layer (Nd).")
        ] = None,
        contact: Annotated[
            Literal["dynamics", "winkler"],
            typer.Option(
                "--contact",
                help="dynamics (the multibody simulation) or winkler (prescribed load, for tests).",
            ),
        ] = "dynamics",
        figure: Annotated[
            Path | None, typer.Option("--figure", help="Also write a PNG of the final wear map.")
        ] = None,
        progress: Annotated[
            bool | None,
            typer.Option("--progress/--no-progress", help="Progress bar (default: on a terminal)."),
        ] = None,
    ) -> None:
        """Simulate Archard wear of joint C over many cycles; checkpoint after every update."""
        import logging

        from jointwear import io
        from jointwear.errors import BadInputError, SimulationError
        from jointwear.outputs import OutputError, OutputExistsError
        from jointwear.params import to_jsonable
        from jointwear.progress import progress_bar
        from jointwear.sim.wear._loop import WearRun
        from jointwear.sim.wearmap import BearingGrid

        # the accuracy warning is printed below with the result; without this handler Python's
        # last-resort handler would print it a second time
        logging.getLogger("jointwear.sim.wear").addHandler(logging.NullHandler())
        io.check_writable(out, what="--out")
        if figure is not None:
            io.check_writable(figure, what="--figure")
        ckpt = checkpoint if checkpoint is not None else out.with_name(out.name + ".ckpt")
        io.check_writable(ckpt, what="--checkpoint")
        snaps = _parse_snapshots(snapshots)
        overrides = {"kw": kw, "scheme": scheme, "dn": dn, "tol": tol, "settle_cycles": settle}
        settings, rest = _load_settings(params, overrides)
        if contact == "dynamics":
            sim_params = _sim_parameters(params, rest, (layers, points), base)
            from jointwear.sim.wear._contact import DynamicContact

            model = DynamicContact(sim_params)
        elif contact == "winkler":
            if rest:
                raise BadInputError(
                    f"--params '{params}': tables {', '.join(rest)} are simulator parameters, "
                    "not used by --contact winkler; give only a [wear] table"
                )
            model = demo_winkler_contact(BearingGrid(layers or 20, points or 200))
        else:
            raise BadInputError(f"--contact must be 'dynamics' or 'winkler', got {contact!r}")
        if not resume and ckpt.exists():
            if not overwrite:  # the state of an earlier run: never thrown away unasked
                raise OutputExistsError(
                    f"checkpoint '{ckpt}' of an earlier run exists; continue that run with "
                    "--resume, or give --overwrite to start over"
                )
            typer.echo(
                f"note: replacing the old checkpoint {ckpt} (use --resume to continue it)", err=True
            )
            ckpt.unlink()

        with progress_bar("wear", total=float(cycles), enabled=progress) as bar:
            task = bar.tasks[0].id

            def on_update(info: dict[str, Any]) -> None:
                bar.update(
                    task,
                    completed=info["cycles_done"],
                    description=(
                        f"wear: dN={info['dn']:d} max depth={info['max_depth'] * 1e6:.2f} µm"
                        + ("" if info["accepted"] else " (rejected, retrying)")
                    ),
                )

            if resume:
                run = WearRun.resume(
                    ckpt, model, settings, cycles=cycles, snapshots=snaps, on_update=on_update
                )
            else:
                run = WearRun(
                    model,
                    settings,
                    cycles=cycles,
                    snapshots=snaps,
                    checkpoint=ckpt,
                    on_update=on_update,
                )
            bar.update(task, completed=run.cycles_done)
            provenance_params = {"wear": to_jsonable(settings), "contact": model.describe()}
            inputs = [params] if params is not None else []
            try:
                ds = run.run()
            except KeyboardInterrupt:
                io.save(
                    run.to_dataset(),
                    out,
                    inputs=inputs,
                    parameters=provenance_params,
                    source=source_attribute("sim.wear"),
                )
                typer.echo(
                    f"interrupted after {run.cycles_done} cycles: partial wear map in {out}, "
                    f"checkpoint in {ckpt}; continue with --resume",
                    err=True,
                )
                raise
            except OutputError as exc:  # full disk while checkpointing: the last checkpoint stands
                raise _resumable(exc, run.cycles_done, ckpt) from exc
            except SimulationError as exc:
                io.save(
                    run.to_dataset(),
                    out,
                    inputs=inputs,
                    parameters=provenance_params,
                    source=source_attribute("sim.wear"),
                )
                raise SimulationError(
                    f"{exc} [wear run stopped after {run.cycles_done} cycles; the wear map so far "
                    f"is in {out}, the last good state in {ckpt}]"
                ) from exc
        try:
            io.save(
                ds,
                out,
                inputs=inputs,
                parameters=provenance_params,
                source=source_attribute("sim.wear"),
            )
        except OutputError as exc:
            raise _resumable(exc, run.cycles_done, ckpt) from exc
        if figure is not None:
            import matplotlib

            matplotlib.use("Agg")
            from jointwear.sim.wearmap import plot_wear_map

            fig = plot_wear_map(ds, kind="both")
            with io.atomic_path(figure) as tmp:
                fig.savefig(tmp, dpi=110, format="png")
        for key in ("convergence_warning", "accuracy_warning"):
            if key in ds.attrs:
                typer.echo(f"warning: {ds.attrs[key]}", err=True)
        u_max = float(ds["max_wear_depth_u"][-1])
        u_vol = float(ds["worn_volume_u"][-1])
        pm = (lambda u, f: f" ± {u * f:.2g}") if u_max == u_max else (lambda u, f: "")
        typer.echo(
            f"{out}: {run.cycles_done} cycles, max depth "
            f"{float(ds['max_wear_depth'][-1]) * 1e6:.2f}{pm(u_max, 1e6)} µm, worn volume "
            f"{float(ds['worn_volume'][-1]) * 1e9:.4g}{pm(u_vol, 1e9)} mm³ "
            f"(accuracy {ds.attrs['accuracy_status']}, k = 2), {ds.attrs['n_updates']} updates, "
            f"{run.cycles_simulated:g} cycles simulated"
        )

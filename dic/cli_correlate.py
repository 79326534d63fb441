"""``jointwear dic correlate``: 2D subset DIC of an image pair or a sequence (folder/video)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite
from jointwear.errors import BadInputError


def _parse_roi(text: str | None):
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        vals = []
    if len(vals) != 4:
        raise BadInputError(
            f"--roi {text!r}: expected four numbers x_min,y_min,x_max,y_max (pixels)"
        )
    return vals


def _parse_points(texts: list[str] | None):
    if not texts:
        return None
    import numpy as np

    out = []
    for t in texts:
        try:
            x, y = (float(v) for v in t.split(","))
        except ValueError:
            raise BadInputError(f"--seed {t!r}: expected x,y in pixels") from None
        out.append((x, y))
    return np.array(out)


def read_points_file(path: Path):
    """Points of interest from a text file: one ``x, y`` [pixel] per line (comma or blank
    separated; ``#`` comments and a non-numeric header line are skipped)."""
    import numpy as np

    if not path.is_file():
        raise BadInputError(f"--points '{path}' does not exist")
    rows = []
    for k, line in enumerate(path.read_text(errors="replace").splitlines(), start=1):
        text = line.split("#", 1)[0].replace(",", " ").replace(";", " ").split()
        if not text:
            continue
        try:
            vals = [float(v) for v in text]
        except ValueError:
            if not rows and k == 1:
                continue  # a header line
            raise BadInputError(
                f"--points '{path}' line {k}: {line.strip()!r} is not two numbers x, y (pixels)"
            ) from None
        if len(vals) != 2:
            raise BadInputError(
                f"--points '{path}' line {k}: expected two numbers x, y (pixels), got {len(vals)}"
            )
        rows.append(vals)
    if not rows:
        raise BadInputError(f"--points '{path}' holds no points (expected lines 'x, y' in pixels)")
    return np.array(rows)


def register(app: typer.Typer) -> None:
    """Add ``correlate`` to the ``jointwear dic`` group."""

    @app.command("correlate")
    def correlate_cmd(
        reference: Annotated[
            Path,
            typer.Argument(
                help="Reference image, or a folder of frames, a quoted pattern ('f/*_0.tif') "
                "or a video (sequence)."
            ),
        ],
        deformed: Annotated[
            Path | None, typer.Argument(help="Deformed image (omit for a sequence).")
        ] = None,
        out: Annotated[Path, typer.Option("--out", help="Output netCDF file.")] = Path("field.nc"),
        overwrite: Overwrite = False,
        roi: Annotated[
            str | None, typer.Option("--roi", help="Region x_min,y_min,x_max,y_max (pixels).")
        ] = None,
        subset: Annotated[
            int, typer.Option("--subset", min=3, help="Subset size (pixels), odd.")
        ] = 31,
        step: Annotated[int, typer.Option("--step", min=1, help="Grid step (pixels).")] = 10,
        shape: Annotated[
            Literal["affine", "quadratic"],
            typer.Option("--shape", help="Shape function: affine or quadratic."),
        ] = "affine",
        interpolation: Annotated[
            Literal["quintic", "cubic"],
            typer.Option("--interpolation", help="B-spline: quintic or cubic."),
        ] = "quintic",
        search_radius: Annotated[
            int, typer.Option("--search-radius", help="Seed search half-width (pixels).")
        ] = 48,
        seed: Annotated[
            list[str] | None,
            typer.Option("--seed", help="Seed point x,y (pixels) (repeatable)."),
        ] = None,
        zncc_min: Annotated[
            float, typer.Option("--zncc-min", help="Flag matches below this ZNCC.")
        ] = 0.8,
        points: Annotated[
            Path | None,
            typer.Option(
                "--points",
                help="Text file of subset centres 'x, y' (pixels, one per line) instead of a grid.",
            ),
        ] = None,
        tolerance: Annotated[
            float,
            typer.Option("--tolerance", help="IC-GN convergence: last update norm (pixels)."),
        ] = 1e-3,
        max_iterations: Annotated[
            int, typer.Option("--max-iterations", help="IC-GN iteration limit per point.")
        ] = 40,
        update_zncc: Annotated[
            float,
            typer.Option(
                "--update-zncc",
                help="Incremental: move the reference forward when the median ZNCC drops below.",
            ),
        ] = 0.9,
        update_every: Annotated[
            int | None,
            typer.Option(
                "--update-every",
                help="Incremental: also move the reference after this many frames (1: always).",
            ),
        ] = None,
        reference_mode: Annotated[
            Literal["absolute", "incremental"],
            typer.Option(
                "--sequence-mode",
                help="Sequences: absolute (every frame against the first) or incremental "
                "(against the previous one).",
            ),
        ] = "absolute",
        frame_rate: Annotated[
            float | None,
            typer.Option("--fps", "--frame-rate", help="Sequences: frame rate (1/s)."),
        ] = None,
        plot: Annotated[
            Path | None, typer.Option("--plot", help="Write a quick-look figure (png).")
        ] = None,
        threads: Annotated[
            int, typer.Option("--threads", min=0, help="numba threads (0: auto).")
        ] = 0,
    ) -> None:
        """Subset DIC (ZNSSD, IC-GN): displacement u, v (pixels) on a grid, written to netCDF."""
        import time as _time

        from jointwear._version import __version__
        from jointwear.dic.subset._correlator import CorrelationParams, SubsetCorrelator
        from jointwear.dic.subset._quicklook import save_quicklook
        from jointwear.dic.subset._sequence import correlate_sequence, read_frames, read_image
        from jointwear.io import check_writable, save
        from jointwear.progress import progress_bar

        check_writable(out)
        if plot is not None:
            check_writable(plot, what="figure")
        params = CorrelationParams(
            subset_size=subset,
            step=step,
            shape=shape,  # type: ignore[arg-type]
            interpolation=interpolation,  # type: ignore[arg-type]
            search_radius=search_radius,
            zncc_min=zncc_min,
            tolerance=tolerance,
            max_iterations=max_iterations,
            threads=threads,
        )
        roi_vals = _parse_roi(roi)
        seeds = _parse_points(seed)
        if points is not None and roi_vals is not None:
            raise typer.BadParameter("give either --points or --roi, not both")
        pts = read_points_file(points) if points is not None else None
        if reference_mode != "incremental" and (update_every is not None or update_zncc != 0.9):
            raise typer.BadParameter(
                "--update-zncc/--update-every apply to --reference incremental only"
            )
        t0 = _time.perf_counter()
        if deformed is None:
            from jointwear.dic.footage._video import is_image_sequence

            if not reference.exists() and not is_image_sequence(reference):
                raise BadInputError(f"'{reference}' does not exist")
            frames, fps = read_frames(reference)
            ds = correlate_sequence(
                (frames, fps),
                reference=reference_mode,
                roi=roi_vals,
                points=pts,
                frame_rate=frame_rate,
                update_zncc=update_zncc,
                update_every=update_every,
                seed_points=seeds,
                progress=None,
                params=params,
            )
            inputs = [reference] if reference.is_file() else []
        else:
            ref_img = read_image(reference)
            def_img = read_image(deformed)
            with progress_bar("correlating", total=2, enabled=None) as bar:
                task = bar.tasks[0].id
                corr = SubsetCorrelator(ref_img, roi=roi_vals, points=pts, params=params)
                bar.update(task, advance=1, description=f"correlating {corr.n_points} points")
                ds = corr.correlate(def_img, seed_points=seeds)
                bar.update(task, advance=1)
            inputs = [reference, deformed]
        elapsed = _time.perf_counter() - t0
        save(
            ds,
            out,
            inputs=inputs,
            parameters=params,
            source=f"jointwear {__version__} (dic.correlate)",
        )
        ok = ds["flag"].values == 0
        msg = (
            f"{out}: {ok.sum()}/{ok.size} points ok, median ZNCC "
            f"{float(ds['zncc'].where(ds['flag'] == 0).median()):.4f}, {elapsed:.2f} s"
        )
        if plot is not None:
            save_quicklook(ds, plot, title=reference.name)
            msg += f"; figure {plot}"
        typer.echo(msg)

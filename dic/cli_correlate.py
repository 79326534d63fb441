"""``jointwear dic correlate``: 2D subset DIC of an image pair or a sequence (folder/video)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import Opt, options_from
from jointwear.dic import _cli_options as opt
from jointwear.dic.subset._params import UPDATE_ZNCC, CorrelationParams
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


def _refuse_misapplied(ctx_params: dict, sequence: bool) -> None:
    """Usage errors (exit 2): sequence options on a pair, incremental options without it."""
    if ctx_params["points"] is not None and ctx_params["roi"] is not None:
        raise typer.BadParameter("give either --points or --roi, not both")
    if not sequence:
        opt.refuse_given(
            (
                (ctx_params["reference_mode"], "--sequence-mode"),
                (ctx_params["frame_rate"], "--fps"),
            ),
            "a sequence (a folder, pattern or video), not to a pair of images",
        )
    if ctx_params["reference_mode"] != "incremental" and (
        ctx_params["update_every"] is not None or ctx_params["update_zncc"] != UPDATE_ZNCC
    ):
        raise typer.BadParameter(
            "--update-zncc/--update-every apply to --sequence-mode incremental only"
        )


def _summary(ds, out: Path, elapsed: float, plot: Path | None, mode, update_zncc) -> str:
    """The command's report line; ``ds`` a Dataset or a Record (read through ``.values``)."""
    import numpy as np

    flag, zncc = ds["flag"].values, ds["zncc"].values
    later = ""
    if "time" in ds["flag"].dims:  # a sequence: the reference frame matches itself (ZNCC 1)
        flag, zncc = flag[1:], zncc[1:]
        later = f" in the {len(flag)} later frame{'s' if len(flag) > 1 else ''}"
    ok = flag == 0
    zncc = zncc[ok & np.isfinite(zncc)]
    median = f"{np.median(zncc):.4f}" if zncc.size else "- (no point ok)"
    msg = f"{out}: {ok.sum()}/{ok.size} points ok{later}, median ZNCC {median}, {elapsed:.2f} s"
    if plot is not None:
        msg += f"; figure {plot}"
    if mode == "incremental":
        moves = int(ds.attrs.get("dic_reference_updates", 0))
        msg += (
            f"; reference moved {moves} time(s)"
            if moves
            else "; the reference never moved (every frame matched frame 0 with a median "
            f"ZNCC above --update-zncc {update_zncc}: the result is the absolute one; "
            "--update-every N moves it every N frames)"
        )
    return msg


@options_from(
    "params",
    CorrelationParams,
    *opt.CORRELATION,
    Opt("shape", help="Shape function: affine or quadratic."),
    Opt("interpolation", help="B-spline: quintic or cubic."),
    Opt(
        "tolerance",
        help="IC-GN convergence: last update norm, or its predicted remaining error (pixels).",
    ),
    "max_iterations",
)
def correlate_cmd(
    ctx: typer.Context,
    reference: Annotated[
        Path,
        typer.Argument(
            help="Reference image, or a folder of frames, a quoted pattern ('f/*_0.tif') "
            "or a video (sequence)."
        ),
    ],
    deformed: Annotated[
        Path | None,
        typer.Argument(
            help="Deformed image; or a folder / quoted pattern of the later frames of a "
            "sequence whose reference is REFERENCE (named unlike them); omit for a "
            "sequence in REFERENCE."
        ),
    ] = None,
    out: opt.OutOpt = Path("field.nc"),
    overwrite: Overwrite = False,
    roi: Annotated[
        str | None, typer.Option("--roi", help="Region x_min,y_min,x_max,y_max (pixels).")
    ] = None,
    params: CorrelationParams = CorrelationParams(),
    seed: Annotated[
        list[str] | None,
        typer.Option("--seed", help="Seed point x,y (pixels) (repeatable)."),
    ] = None,
    points: opt.PointsOpt = None,
    update_zncc: Annotated[
        float,
        typer.Option(
            "--update-zncc",
            help="Incremental: move the reference forward when the median ZNCC drops below.",
        ),
    ] = UPDATE_ZNCC,
    update_every: Annotated[
        int | None,
        typer.Option(
            "--update-every",
            help="Incremental: also move the reference after this many frames (1: always).",
        ),
    ] = None,
    reference_mode: Annotated[
        Literal["absolute", "incremental"] | None,
        typer.Option(
            "--sequence-mode",
            help="Sequences: absolute (every frame against the first; default) or "
            "incremental (the reference moves forward to a later frame when the matches "
            "against it degrade, or every --update-every frames).",
        ),
    ] = None,
    frame_rate: Annotated[
        float | None,
        typer.Option("--fps", "--frame-rate", help="Sequences: frame rate (1/s)."),
    ] = None,
    plot: opt.PlotOpt = None,
    allow_empty: opt.AllowEmptyOpt = False,
    origin: opt.OriginOpt = "measured",
) -> None:
    """Subset DIC (ZNSSD, IC-GN): displacement u, v (pixels) on a grid, written to netCDF."""
    from jointwear.dic._flag_report import check_flags
    from jointwear.dic.subset._files import correlate_files, is_sequence_input

    _refuse_misapplied(ctx.params, is_sequence_input(deformed))
    ds, elapsed = correlate_files(
        reference,
        deformed,
        out,
        params=params,
        roi=_parse_roi(roi),
        points=points,
        seed_points=_parse_points(seed),
        reference_mode=reference_mode,
        frame_rate=frame_rate,
        update_zncc=update_zncc,
        update_every=update_every,
        plot=plot,
        data_origin=origin,
    )
    typer.echo(_summary(ds, out, elapsed, plot, reference_mode, update_zncc))
    check_flags(ds, allow_empty=allow_empty)


def register(app: typer.Typer) -> None:
    """Add ``correlate`` to the ``jointwear dic`` group."""
    app.command("correlate")(correlate_cmd)

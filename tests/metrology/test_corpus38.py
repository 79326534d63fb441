"""Issue 38 "done when": a fresh corpus of 60 exports of the kinds the issue lists (comma CSVs
with 3 decimals, long z,angle,dev files with angles >= 100, a sub-um form under a wrong
``Units: mm``, filter claims on truly filtered traces, missing values, space/apostrophe
thousands, heights in an index file, merged Excel headers, micro-inch, unknown header units,
two probes), each with known truth, imported through the command line as a new user would:
first with only the convention; then every suggestion of every refusal, *as printed* on
stderr, split by the shell's rules (:func:`shlex.split`) and appended to the command. Nothing
is read wrong with exit 0; every refusal names a flag; every printed suggestion is accepted by
the CLI (never a usage error); a suggestion consistent with the truth reads the file right or
refuses again with another message; every file ends up read right.

The command runs in process (``jointwear.cli.main``) for the whole corpus and, for one file of
each refused kind, in a subprocess (``python -m jointwear``); the ``slow`` test runs the rest
of the corpus in subprocesses."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from jointwear._cli import speak_flags
from jointwear.metrology.readers import read_scan
from jointwear.metrology.readers.advice import Refusal, advise

BASE = ["--angle-zero", "-x", "--angle-direction", "clockwise"]  # canonical: theta as written
KINDS = (
    "comma3",
    "long_comma",
    "semicolon_space",
    "small_form",
    "filtered",
    "missing",
    "heights",
    "merged",
    "uin",
    "unknown_unit",
    "probes",
    "apostrophe",
)


def _dev(rng, n, layers):
    t = np.radians(np.arange(n) * 360.0 / n)
    a = rng.uniform(0.1, 0.4, layers)
    return np.array([a[k] * np.cos(2 * t + k) + 0.05 * np.sin(7 * t) for k in range(layers)])


def _wide(head: str, th, zs, values, cell, *, sep="\t", name="z={z:g}mm", angle="{:.1f}") -> str:
    """A wide export's text: the ``head`` lines, the column names (the angle's, then one per
    layer at ``zs`` [mm]), then per angle ``th`` the angle and each layer's ``cell(value)``."""
    names = sep.join(name.format(z=z) for z in zs)
    rows = "".join(
        angle.format(t) + sep + sep.join(cell(v[i]) for v in values) + "\n"
        for i, t in enumerate(th)
    )
    return f"{head}Angle (deg){sep}{names}\n{rows}"


def _write(kind: str, d, rng):
    """Write one export of ``kind``; return (input path, truth, fill) with truth = (theta
    [degree], z [m] from mid-width, values [m], variable) and fill the placeholder values."""
    n = int(rng.choice([360, 720]))
    th = np.arange(n) * 360.0 / n
    layers = int(rng.integers(2, 4))
    zs = np.arange(layers) * float(rng.choice([0.5, 1.0, 2.0]))  # mm
    fill = {"<mm>": f"{zs[1] - zs[0]:g}" if layers > 1 else "1", "<unit>": "um", "--units": "um"}
    var = "radial_deviation"
    dev = np.round(_dev(rng, n, layers), 3)  # um
    f = d / "scan.csv"
    if kind == "comma3":
        head = ",".join(["Angle (deg)"] + [f"Dev z={z:g} mm" for z in zs])
        body = "".join(
            ",".join([f"{th[i]:.{int(rng.integers(1, 4))}f}"] + [f"{v[i]:.3f}" for v in dev]) + "\n"
            for i in range(n)
        )
        f.write_text(f"Units: um\n{head}\n{body}")
    elif kind == "long_comma":
        f.write_text(
            "Units: um\nz,angle,dev\n"
            + "".join(
                f"{z:.3f},{th[i]:.2f},{dev[k][i]:.3f}\n" for k, z in enumerate(zs) for i in range(n)
            )
        )
        fill["<unit>"] = fill["--z-units"] = "mm"  # the z column's unit
    elif kind == "semicolon_space":  # radii in um, decimal comma, space thousands
        var = "radius"
        dev = np.round(8000.0 + dev, 3)
        f.write_text(
            "Units: um\nWinkel;"
            + ";".join(f"Radius z={z:g} mm" for z in zs)
            + "\n"
            + "".join(
                f"{th[i]:.1f};".replace(".", ",")
                + ";".join(f"{v[i]:,.3f}".replace(",", " ").replace(".", ",") for v in dev)
                + "\n"
                for i in range(n)
            )
        )
    elif kind == "small_form":  # um values under a false "Units: mm" with the bore stated
        layers, zs, dev = 1, zs[:1], dev[:1]
        fill["--ignore-header"] = "units"
        f.write_text(
            "Units: mm\nNominal diameter: 25 mm\nAngle (deg),Deviation\n"
            + "".join(f"{th[i]:.1f},{dev[0][i]:.3f}\n" for i in range(n))
        )
    elif kind == "filtered":
        from jointwear.metrology.filters import filter_profile

        kc = float(rng.choice([15, 50]))
        raw = _dev(rng, n, layers) + 0.01 * rng.standard_normal((layers, n))
        dev = np.round(filter_profile(raw * 1e-6, kc) * 1e6, 4)
        head = f"Units: um\nFilter: Gaussian {kc:g} UPR\n"
        f.write_text(_wide(head, th, zs, dev, "{:.4f}".format, angle="{:.2f}"))
    elif kind == "missing":
        mark = str(rng.choice(["---", "NaN", "nan", "", "-", "*", "n/a"]))
        gone = rng.choice(n * layers, size=layers * n // 100, replace=False)
        dev = dev.astype(float)
        dev.flat[gone] = np.nan
        sep = str(rng.choice([",", ";", "\t"]))
        cell = lambda v: mark if np.isnan(v) else f"{v:.3f}"  # noqa: E731
        f.write_text(_wide("Units: um\n", th, zs, dev, cell, sep=sep, name="Dev z={z:g} mm"))
    elif kind == "heights":
        f = d / "scan"
        f.mkdir()
        zs = np.cumsum(rng.uniform(0.5, 2.0, layers)) - 0.5  # uneven
        for k in range(layers):
            (f / f"trace{k + 1}.txt").write_text(
                "Units: um\nAngle (deg)\tDeviation\n"
                + "".join(f"{th[i]:.1f}\t{dev[k][i]:.3f}\n" for i in range(n))
            )
        if rng.integers(2):
            (f / "heights.txt").write_text(
                "".join(f"trace{k + 1}.txt {z:.3f}\n" for k, z in enumerate(zs))
            )
            fill["<unit>"] = fill["--z-units"] = "mm"
        else:
            (f / "index.csv").write_text(
                "file,height_mm\n"
                + "".join(f"trace{k + 1}.txt,{z:.3f}\n" for k, z in enumerate(zs))
            )
        zs = np.round(zs, 3)
    elif kind == "merged":
        import openpyxl

        f = d / "scan.xlsx"
        wb = openpyxl.Workbook()
        ws = wb.active
        ws.append(["Units", "um"])
        ws.append([c for k, z in enumerate(zs) for c in (f"Layer {k + 1}  z = {z:.1f} mm", None)])
        ws.append(["Angle (deg)", "Deviation (um)"] * layers)
        for i in range(n):
            ws.append([c for k in range(layers) for c in (float(th[i]), float(dev[k][i]))])
        wb.save(f)
    elif kind == "uin":
        dev = np.round(dev * 40.0, 2)  # in micro-inch
        fill["--units"] = "uin"
        f.write_text(_wide("Units: uin\n", th, zs, dev, "{:.2f}".format))
        return f, (th, (zs - 0.5 * (zs.min() + zs.max())) * 1e-3, dev * 25.4e-9, var), fill
    elif kind == "unknown_unit":
        f.write_text(_wide("Einheit: Mikrometer\n", th, zs, dev, "{:.3f}".format))
    elif kind == "probes":  # two angle/value pairs: two probes, the first one is the truth
        layers, zs = 1, zs[:1]
        other = np.round(_dev(rng, n, 1)[0], 3)
        f.write_text(
            "Units: um\nAngle (deg)\tDeviation\tAngle (deg)\tDeviation\n"
            + "".join(
                f"{th[i]:.1f}\t{dev[0][i]:.3f}\t{th[i]:.1f}\t{other[i]:.3f}\n" for i in range(n)
            )
        )
        dev = dev[:1]
        fill["--columns"] = "angle_deg,deviation,ignore,ignore"
    else:  # apostrophe: radii in nm as grouped integers
        var = "radius"
        nm = np.round((8000.0 + dev) * 1000.0)
        fill["--thousands"], fill["--units"] = "apostrophe", "nm"
        grouped = lambda v: f"{int(v):,}".replace(",", "'")  # noqa: E731
        f.write_text(_wide("Units: nm\n", th, zs, nm, grouped, name="Radius z={z:g} mm"))
        return f, (th, (zs - 0.5 * (zs.min() + zs.max())) * 1e-3, nm * 1e-9, var), fill
    return f, (th, (zs - 0.5 * (zs.min() + zs.max())) * 1e-3, dev * 1e-6, var), fill


def _run(argv: list[str], sub: bool, capsys) -> tuple[int, str]:
    if sub:
        p = subprocess.run(
            [sys.executable, "-m", "jointwear", *argv], capture_output=True, text=True, timeout=120
        )
        return p.returncode, p.stderr
    from jointwear.cli import main

    code = main(argv)
    return code, capsys.readouterr().err


def _printed(exc: Refusal) -> list[str]:
    """Each suggestion of a refusal as the command line prints it (``--flag value ...``)."""
    import typer
    from typer.main import get_command

    from jointwear.metrology.cli_metrology import import_cmd

    app = typer.Typer()
    app.command()(import_cmd)
    params = get_command(app).params
    return [speak_flags(advise([(s, "")])[0], params)[len("pass ") :] for s in exc.suggestions]


def _filled(words: list[str], fill: dict, argv: list[str]) -> list[str] | None:
    """``argv`` with the printed flags added (placeholders filled from the truth; 'without
    --flag' removes it); None when a placeholder has no truth value."""
    out = list(argv)
    i = 0
    while i < len(words):
        w = words[i]
        if w == "without":
            flag = words[i + 1]
            if flag in out:
                k = out.index(flag)
                del out[k : k + 2]
            i += 2
            continue
        if w.startswith("<"):
            if w not in fill:
                return None
            w = fill[w]
        out.append(w)
        i += 1
    return out


def _right(path, truth) -> None:
    th, z, v, var = truth
    ds = xr.load_dataset(path)
    assert var in ds, f"read as {list(ds.data_vars)}, truth {var}"
    np.testing.assert_allclose(ds["theta"].values, th, atol=1e-6, err_msg="theta misread")
    np.testing.assert_allclose(ds["z"].values, z, atol=1e-9, err_msg="z misread")
    np.testing.assert_allclose(ds[var].values, v, rtol=1e-9, atol=1e-15, err_msg="values misread")


def _follow(path, truth, fill, argv, sub, capsys, tmp, seen=(), depth=0) -> bool:
    """Import with ``argv``; on exit 0 the read must be the truth; on a refusal, run every
    printed suggestion. True when some route reads the file right."""
    out = tmp / f"o{depth}_{len(seen)}.nc"
    code, err = _run(
        ["metrology", "import", str(path), "--out", str(out), *BASE, *argv], sub, capsys
    )
    assert code != 2, f"usage error for {argv}: {err}"
    if code == 0:
        _right(out, truth)
        return True
    assert code == 3, err
    msg = err.strip()
    assert msg not in seen, f"a printed suggestion led back to the same refusal: {msg}"
    assert re.search(r"--[a-z]", msg), f"a refusal names no flag: {msg}"
    try:
        read_scan(path, convention=("-x", "clockwise"), **_library(argv, fill))
    except Refusal as exc:
        printed = _printed(exc)
    else:  # pragma: no cover - the library and the CLI must agree
        raise AssertionError(f"the CLI refused what the library reads: {msg}")
    if depth >= 3:
        return False
    right = False
    for k, text in enumerate(printed):
        assert text in msg, f"suggestion {text!r} not printed as such in: {msg}"
        words = shlex.split(text)
        new = _filled(words, fill, argv)
        if new is None:
            continue
        if _consistent(words, fill):
            right |= _follow(path, truth, fill, new, sub, capsys, tmp, (*seen, msg), depth + 1)
        else:  # another reading of the file: the command line must still take it as printed
            o = tmp / f"alt{depth}_{k}.nc"
            code, err = _run(
                ["metrology", "import", str(path), "--out", str(o), *BASE, *new], sub, capsys
            )
            assert code in (0, 3), f"{text!r} as printed: exit {code}: {err}"
    return right


def _consistent(words: list[str], truth: dict) -> bool:
    """A printed suggestion agrees with the truth of the file (flags the truth names must have
    its value; flags it does not name are other readings of the file)."""
    flags = [w for w in words if w.startswith("--")]
    for f in flags:
        i = words.index(f)
        if f not in truth:
            return False
        if i + 1 < len(words) and not words[i + 1].startswith("<") and words[i + 1] != truth[f]:
            return False
    return True


def _library(argv: list[str], fill: dict) -> dict:
    """The read_scan keywords of the CLI flags used so far (to get the refusal's data)."""
    kw: dict = {}
    it = iter(argv)
    for flag in it:
        name = flag[2:].replace("-", "_")
        val = next(it)
        if name == "ignore_header":
            kw["ignore_header"] = (*kw.get("ignore_header", ()), val)
        elif name == "layer_spacing_mm":
            kw["layer_spacing"] = float(val) * 1e-3
        elif name == "z_mm":
            kw["z"] = [float(x) * 1e-3 for x in val.split(",")]
        elif name in ("max_missing", "form_fraction"):
            kw[name] = float(val)
        else:
            kw[name] = val
    return kw


#: Kinds the natural command refuses (their printed suggestions are what runs as printed).
REFUSED = ("long_comma", "small_form", "heights", "unknown_unit", "probes", "apostrophe")
CORPUS = [(kind, seed) for seed in range(5) for kind in KINDS]  # 60 exports


@pytest.mark.parametrize(("kind", "seed"), CORPUS)
def test_corpus_reads_right_by_the_natural_command_or_a_printed_suggestion(
    tmp_path, capsys, kind, seed
):
    rng = np.random.default_rng(1000 * seed + KINDS.index(kind))
    path, truth, fill = _write(kind, tmp_path, rng)
    sub = seed == 0 and kind in REFUSED  # one refused file of each kind through a subprocess
    assert _follow(path, truth, fill, [], sub, capsys, tmp_path), (
        f"{kind}: no route to a right read"
    )


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "seed"), [c for c in CORPUS if c[1] > 0])
def test_corpus_through_subprocesses(tmp_path, capsys, kind, seed):
    rng = np.random.default_rng(1000 * seed + KINDS.index(kind))
    path, truth, fill = _write(kind, tmp_path, rng)
    assert _follow(path, truth, fill, [], True, capsys, tmp_path), f"{kind}: no route"

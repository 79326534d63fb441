"""Reading and writing jointwear files: netCDF with units and provenance, written atomically.

``save`` writes to a temporary file in the destination folder and renames it over the target
only when the write succeeded, so a crash never leaves a half-written file or clobbers the
previous one. Attributes netCDF cannot store (booleans, dicts, lists of mixed type, None) are
encoded as JSON strings with the prefix ``"json:"`` and decoded by ``load``.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from jointwear import outputs
from jointwear._version import source_attribute
from jointwear.errors import BadInputError
from jointwear.provenance import build_provenance, dumps, history_line, sha256_file

if TYPE_CHECKING:  # xarray is imported where a Dataset is read or written (start-up cost)
    import xarray as xr

__all__ = [
    "save",
    "load",
    "load_header",
    "atomic_path",
    "save_figure",
    "figure_format",
    "check_writable",
    "encode_attrs",
    "decode_attrs",
    "parse_provenance",
    "file_snapshot",
    "file_attrs",
]

_JSON_PREFIX = "json:"


def _encode_value(value: Any) -> Any:
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, Mapping):
        return _JSON_PREFIX + json.dumps(value if not isinstance(value, np.bool_) else bool(value))
    if isinstance(value, (list, tuple)):
        if len(value) and all(
            isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in value
        ):
            return np.asarray(value)
        if len(value) and all(isinstance(v, str) for v in value):
            return _JSON_PREFIX + json.dumps(list(value))
        return _JSON_PREFIX + json.dumps(list(value), default=str)
    if isinstance(value, Path):
        return str(value)
    return value


def encode_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Encode attribute values netCDF cannot store as ``"json:..."`` strings."""
    return {k: _encode_value(v) for k, v in attrs.items()}


def decode_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Inverse of :func:`encode_attrs`."""
    out = {}
    for k, v in attrs.items():
        if isinstance(v, str) and v.startswith(_JSON_PREFIX):
            try:
                v = json.loads(v[len(_JSON_PREFIX) :])
            except ValueError:
                pass
        out[k] = v
    return out


def check_writable(path: str | Path, *, what: str = "output") -> Path:
    """Fail early (before a long computation) if the file ``path`` cannot be written.

    Creates the parent folder if needed and tries a temporary file there
    (:func:`jointwear.outputs.check_location`); a folder, or a place that cannot be written, is
    a :class:`~jointwear.errors.BadInputError` (the path given is the problem).
    """
    path = Path(path)
    if path.is_dir():
        raise BadInputError(f"{what} path '{path}' is a folder; give a file name")
    try:
        return outputs.check_location(path, what=what)
    except outputs.OutputError as exc:
        raise BadInputError(str(exc)) from None


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it over ``path`` if the block succeeds.

    While the block runs, the output's lock is held (another process writing ``path`` makes
    this raise :class:`~jointwear.outputs.OutputBusyError`), stale temporary files of ``path``
    left by a killed writer are removed first, and a failed write (full disk, permission,
    netCDF/HDF error) becomes an :class:`~jointwear.outputs.OutputError` naming ``path``; the
    previous file, if any, is left as it was.

    Use for any file type::

        with atomic_path("report.html") as tmp:
            tmp.write_text(html)
    """
    path = Path(path)
    check_writable(path)
    with outputs.output_lock(path):
        outputs.remove_stale_temporaries(path)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        os.close(fd)
        tmp_path = Path(tmp)
        try:
            yield tmp_path
            with open(tmp_path, "rb") as fh:
                os.fsync(fh.fileno())
            # mkstemp creates 0600 files; give the result the permissions of a normally created
            # file
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp_path, 0o666 & ~umask)
            os.replace(tmp_path, path)
        except Exception as exc:
            if outputs.is_write_failure(exc):
                raise outputs.write_failure(exc, path) from exc
            raise
        finally:
            if tmp_path.exists():
                tmp_path.unlink()


def parse_provenance(ds: xr.Dataset) -> dict[str, Any]:
    """The provenance record of a dataset as a dict (empty if absent)."""
    text = ds.attrs.get("provenance")
    if not text:
        return {}
    try:
        return json.loads(text)
    except (TypeError, ValueError):
        return {}


def file_snapshot(path: str | Path) -> tuple[str, tuple[str, ...]]:
    """What identifies a file's data: its sha256 and the sorted sha256 of the inputs its own
    provenance names (the scans it was made from; empty for a file without readable
    provenance). Two files made from the same scans share the second part."""
    digest = sha256_file(path)
    try:
        prov = parse_provenance(load(path, validate=False))
        inputs = sorted(str(i["sha256"]) for i in prov.get("inputs", []) if i.get("sha256"))
    except (BadInputError, OSError, ValueError, KeyError, TypeError):
        inputs = []
    return digest, tuple(inputs)


def save_figure(fig: Any, path: str | Path, *, dpi: float = 110, what: str = "--out") -> Path:
    """Write a matplotlib figure atomically in the format its file name says.

    The suffix must be one the figure's canvas can write (png, pdf, svg, ...; a name without a
    suffix is written as PNG): anything else (``o.nc``) is refused naming ``what`` and the
    supported formats, before any file is touched.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : path
        Output file.
    dpi : float
        Resolution of a raster format [dots per inch].
    what : str
        How the user named the path (an option, a parameter), for the message.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    fmt = figure_format(path, what=what)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt)
    return path


def figure_format(path: str | Path, *, what: str = "--out") -> str:
    """The figure format a file name asks for (its suffix; none: png), or a refusal.

    Call it before a long computation whose figure goes to ``path``, so that a name matplotlib
    cannot write (``map.nc``) is refused at once, naming ``what`` and the supported formats.
    """
    from matplotlib.backend_bases import FigureCanvasBase

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt not in supported:
        raise BadInputError(
            f"{what} '{path}': a figure cannot be written as '.{fmt}'; use one of "
            + ", ".join(f".{k}" for k in sorted(supported))
            + " (e.g. .png)"
        )
    return fmt


def file_attrs(
    attrs: Mapping[str, Any],
    *,
    inputs: Iterable[str | Path] = (),
    parameters: Any = None,
    command: str | None = None,
    source: str | None = None,
    title: str | None = None,
    parents: Iterable[Mapping[str, Any]] = (),
) -> dict[str, Any]:
    """The global attributes :func:`save` writes: ``attrs`` with ``Conventions``, ``title``,
    ``source``, a new ``history`` line and the ``provenance`` record, encoded for netCDF
    (:func:`encode_attrs`). ``parents`` are provenance records (dicts); without any, the
    provenance already in ``attrs`` is carried along. See :func:`save` for the rest."""
    out = dict(attrs)
    out["Conventions"] = "CF-1.11"
    out["title"] = title or out.get("title") or "jointwear dataset"
    out["source"] = source or out.get("source") or source_attribute()
    line = history_line(command)
    previous = out.get("history")
    out["history"] = f"{previous}\n{line}" if previous else line
    parent_records = list(parents)
    if out.get("provenance") and not parent_records:
        # keep the provenance of the data as it came in
        try:
            parent_records = [json.loads(out["provenance"])]
        except (TypeError, ValueError):
            parent_records = []
    prov = build_provenance(
        inputs=inputs,
        parameters=parameters,
        command=command,
        parents=[p for p in parent_records if p],
    )
    out["provenance"] = dumps(prov)
    return encode_attrs(out)


def save(
    ds: xr.Dataset,
    path: str | Path,
    *,
    inputs: Iterable[str | Path] = (),
    parameters: Any = None,
    command: str | None = None,
    source: str | None = None,
    title: str | None = None,
    parents: Iterable[xr.Dataset] = (),
    validate: bool = True,
) -> Path:
    """Write ``ds`` to netCDF atomically, with units, history and provenance.

    Parameters
    ----------
    ds : Dataset
        Data following the contract of :mod:`jointwear.conventions`.
    path : path
        Destination ``.nc`` file. Its folder is created if needed.
    inputs : iterable of path
        Input files (recorded with sha256 in ``provenance``).
    parameters : object
        Resolved parameters (dataclass or mapping), recorded in full.
    command : str, optional
        Command line; defaults to ``sys.argv``.
    source : str, optional
        CF ``source`` attribute, e.g. ``source_attribute("sim.wear")``; kept from ``ds`` if set.
    title : str, optional
        CF ``title``; kept from ``ds`` if set.
    parents : iterable of Dataset
        Input datasets whose provenance should be carried along.
    validate : bool
        Check the contract (units, conventions) before writing (default True).

    Returns
    -------
    Path
        The written file.
    """
    from jointwear import conventions

    path = Path(path)
    out = ds.copy()
    if validate:
        conventions.validate(out, what=f"dataset to be written to '{path}'")
    out.attrs = file_attrs(
        out.attrs,
        inputs=inputs,
        parameters=parameters,
        command=command,
        source=source,
        title=title,
        parents=[parse_provenance(p) for p in parents],
    )
    for name in list(out.variables):
        out[name].attrs = encode_attrs(out[name].attrs)
    with atomic_path(path) as tmp:
        out.to_netcdf(tmp, engine="netcdf4", format="NETCDF4")
    return path


def _existing(path: str | Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise BadInputError(f"'{path}' does not exist")
    if path.is_dir():
        raise BadInputError(f"'{path}' is a folder, expected a netCDF (.nc) file")
    return path


def _not_netcdf(path: Path, exc: Exception) -> BadInputError:
    return BadInputError(
        f"'{path}' could not be read as netCDF ({exc}); is it a jointwear .nc file?"
    )


def _checked(ds: Any, path: Path, validate: bool) -> None:
    """Decode the attributes of ``ds`` (a Dataset or a :class:`~jointwear._header.Header`) in
    place and check it against the contract (a foreign file is told how it comes in)."""
    from jointwear import conventions

    ds.attrs.update(decode_attrs(ds.attrs))
    for var in [*ds.coords.values(), *ds.data_vars.values()]:
        var.attrs.update(decode_attrs(var.attrs))
    if validate:
        try:
            conventions.validate(ds, require_provenance=True, what=f"'{path}'")
        except BadInputError as exc:
            if "provenance" in ds.attrs:
                raise
            # a file written by another tool: say how it comes in, rather than only what is wrong
            raise type(exc)(
                f"{exc}\n'{path}' was not written by jointwear (no provenance). A file from "
                "another simulator or instrument comes in with 'jointwear import wearmap' or "
                "'jointwear import motion' (--origin simulated|measured|synthetic, and the angle "
                "convention and units when the file does not state them); in Python, "
                "jointwear.external.import_cf. See docs/tutorial-own-data.md."
            ) from None


def load_header(path: str | Path, *, validate: bool = True) -> Any:
    """The header of a jointwear netCDF file (names, dimensions, attributes, coordinate
    values; no data, no xarray), checked against the contract as :func:`load` checks it.

    Returns
    -------
    jointwear._header.Header
        ``attrs``, ``sizes``, ``coords`` and ``data_vars`` as a Dataset has them.
    """
    from jointwear._header import read_header

    path = _existing(path)
    try:
        header = read_header(path)
    except (OSError, ValueError, RuntimeError) as exc:
        raise _not_netcdf(path, exc) from None
    _checked(header, path, validate)
    return header


def load(path: str | Path, *, validate: bool = True) -> xr.Dataset:
    """Read a jointwear netCDF file fully into memory and check it against the contract.

    Raises
    ------
    BadInputError
        The file does not exist, is not netCDF, or breaks the contract (the message lists
        every problem).
    """
    import xarray as xr

    path = _existing(path)
    try:
        with xr.open_dataset(path, engine="netcdf4") as raw:
            ds = raw.load()
    except (OSError, ValueError) as exc:
        raise _not_netcdf(path, exc) from None
    _checked(ds, path, validate)
    ds.encoding["source"] = str(path)
    return ds

"""Checkpoints: safe (no pickle), versioned, exact round trip, clear refusals."""

from __future__ import annotations

import json
import pickle
import zipfile

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.sim import BearingGrid, ConstantContact, WearRun, WearSettings
from jointwear.sim.dynamics import SimState
from jointwear.sim.wear._checkpoint import FORMAT_VERSION, read_checkpoint, write_checkpoint


def test_round_trip_is_exact_for_every_type_the_state_holds(tmp_path):
    rng = np.random.default_rng(5)
    state = {
        "h": rng.standard_normal((3, 4)),
        "ints": np.arange(5, dtype=np.int64),
        "none": None,
        "nan": float("nan"),
        "inf": -float("inf"),
        "third": 1 / 3,
        "big": 2**100 + 1,  # generator states hold 128-bit integers
        "tuple": (1, 2.5, "x"),
        "list": [np.zeros(2), {"a": True}],
        "__weird__": {"__array__": "not an array"},
        "sim": SimState(0.25, rng.standard_normal(7), 1e-4, np.zeros(4), "clearance"),
    }
    path = write_checkpoint(tmp_path / "c.ckpt", {"wear": {"kw": 1e-15}}, state)
    fp, back = read_checkpoint(path)
    assert fp == {"wear": {"kw": 1e-15}}
    np.testing.assert_array_equal(back["h"], state["h"])
    assert back["ints"].dtype == np.int64
    assert back["none"] is None and np.isnan(back["nan"]) and back["inf"] == -np.inf
    assert back["third"] == 1 / 3 and back["big"] == 2**100 + 1
    assert back["tuple"] == (1, 2.5, "x")
    assert back["list"][1] == {"a": True}
    assert back["__weird__"] == {"__array__": "not an array"}
    assert isinstance(back["sim"], SimState)
    np.testing.assert_array_equal(back["sim"].y, state["sim"].y)
    assert back["sim"].time == 0.25
    with zipfile.ZipFile(path) as zf:  # inspectable: JSON + .npy members
        meta = json.loads(zf.read("checkpoint.json"))
    assert meta["version"] == FORMAT_VERSION


class _Boom:
    def __reduce__(self):
        import pathlib

        return (pathlib.Path.touch, (pathlib.Path(self.marker),))


def test_an_old_pickle_checkpoint_is_refused_without_being_unpickled(tmp_path):
    boom = _Boom()
    boom.marker = str(tmp_path / "executed")
    (tmp_path / "old.ckpt").write_bytes(pickle.dumps({"format": "v1", "x": boom}))
    with pytest.raises(BadInputError, match=r"old\.ckpt.*pickle.*format 1.*without --resume"):
        read_checkpoint(tmp_path / "old.ckpt")
    assert not (tmp_path / "executed").exists()


def test_only_jointwear_dataclasses_are_rebuilt(tmp_path):
    path = write_checkpoint(tmp_path / "c.ckpt", {}, {"x": 1})
    with zipfile.ZipFile(path) as zf:
        meta = json.loads(zf.read("checkpoint.json"))
    meta["state"] = {"__dataclass__": "subprocess:Popen", "fields": {"args": "touch pwned"}}
    evil = tmp_path / "evil.ckpt"
    with zipfile.ZipFile(evil, "w") as zf:
        zf.writestr("checkpoint.json", json.dumps(meta))
    with pytest.raises(BadInputError, match="not part of jointwear"):
        read_checkpoint(evil)


@pytest.mark.parametrize(
    ("version", "match"),
    [(FORMAT_VERSION + 1, "newer jointwear"), (0, "cannot continue")],
)
def test_other_format_versions_are_refused_naming_the_file(tmp_path, version, match):
    path = write_checkpoint(tmp_path / "c.ckpt", {}, {"x": 1})
    with zipfile.ZipFile(path) as zf:
        meta = json.loads(zf.read("checkpoint.json"))
    meta["version"] = version
    other = tmp_path / "other.ckpt"
    with zipfile.ZipFile(other, "w") as zf:
        zf.writestr("checkpoint.json", json.dumps(meta))
    with pytest.raises(BadInputError, match=rf"other\.ckpt.*{match}"):
        read_checkpoint(other)


def test_truncated_and_foreign_files_are_refused(tmp_path):
    grid = BearingGrid(3, 8)
    run = WearRun(
        ConstantContact(grid), WearSettings(kw=1e-14), cycles=100, checkpoint=tmp_path / "w.ckpt"
    )
    run.run()
    data = (tmp_path / "w.ckpt").read_bytes()
    (tmp_path / "cut.ckpt").write_bytes(data[: len(data) // 2])
    with pytest.raises(BadInputError, match=r"cut\.ckpt.*could not be read"):
        WearRun.resume(
            tmp_path / "cut.ckpt", ConstantContact(grid), WearSettings(kw=1e-14), cycles=100
        )
    with zipfile.ZipFile(tmp_path / "foreign.ckpt", "w") as zf:
        zf.writestr("checkpoint.json", json.dumps({"format": "something else"}))
    with pytest.raises(BadInputError, match="not a jointwear wear checkpoint"):
        read_checkpoint(tmp_path / "foreign.ckpt")


def test_unstorable_contact_state_is_refused_at_the_first_save(tmp_path):
    class Opaque:
        pass

    class OpaqueContact(ConstantContact):
        def run(self, wear_depth, *, cycles, state, progress=None):
            res = super().run(wear_depth, cycles=cycles, state=state)
            res.state = Opaque()
            return res

    run = WearRun(
        OpaqueContact(BearingGrid(3, 8)),
        WearSettings(kw=1e-14),
        cycles=10,
        checkpoint=tmp_path / "o.ckpt",
    )
    with pytest.raises(BadInputError, match=r"o\.ckpt.*Opaque cannot be checkpointed"):
        run.run()

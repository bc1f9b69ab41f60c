"""The operator cache cannot poison a study: a truncated or corrupt file, a file of an older
format, a file missing an array or holding one of another shape is rebuilt with a warning
and the numbers are those of a fresh build; concurrent jobs writing the same operator both
succeed and leave a complete file; the cache key covers the source that computes the
operators."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

from ssw import cachefile
from ssw.contact import operators as ops
from ssw.contact.operators import CacheWarning, OperatorStore
from ssw.contact.scene import solve_curve

#: A small scene: a PLA plate on a soil, a coarse mesh (operators in a fraction of a second).
CONTACT = {"delta_max": 5e-5, "steps": 50, "mesh_growth": 0.3, "mesh_size_contact": 1.5e-5,
           "soil_radius": 0.1, "soil_depth": 0.1}
SCENE = ((50e6, 0.3), (3.5e9, 0.36), 0.4e-3, 9.53e-3)


def _force(cache: Path) -> np.ndarray:
    curve, _ = solve_curve(*SCENE, CONTACT, OperatorStore(cache))
    return curve.force


def test_every_truncated_or_corrupt_file_is_rebuilt(tmp_path):
    cache = tmp_path / "cache"
    want = _force(cache)
    files = sorted(cache.rglob("*.npz"))
    assert len(files) == 4  # the mesh, the layout, the plate, the soil
    originals = {f: f.read_bytes() for f in files}
    for f in files:
        data = originals[f]
        for bad in (b"", data[: len(data) // 2], data[:-1],
                    data[:100] + bytes(b ^ 0xFF for b in data[100:140]) + data[140:]):
            for g, d in originals.items():
                g.write_bytes(d)
            f.write_bytes(bad)
            if f.name == "model.npz":  # read when an operator is built from it: the layout
                (f.parent / "layout.npz").unlink()
            with pytest.warns(CacheWarning, match="rebuilding"):
                got = _force(cache)
            np.testing.assert_array_equal(got, want)
            with np.load(f) as z:  # rebuilt whole
                assert len(z.files) >= 1 and all(z[k] is not None for k in z.files)


#: The cache files of the scene, by the start of their names, and their formats.
FILES = {"model": ops.MODEL_FORMAT, "layout": ops.LAYOUT_FORMAT, "plate": ops.BODY_FORMAT,
         "soil": ops.BODY_FORMAT}


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    """The scene's force from a fresh build, and the bytes of the files it left (by kind)."""
    cache = tmp_path_factory.mktemp("fresh")
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)  # an empty cache: nothing to rebuild
        force = _force(cache)
    files = {f.name.split("-")[0].removesuffix(".npz"): f for f in cache.rglob("*.npz")}
    assert sorted(files) == sorted(FILES)
    return force, {k: (f.relative_to(cache), f.read_bytes()) for k, f in files.items()}


def _members(data: bytes) -> dict[str, np.ndarray]:
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _npz(arrays: dict[str, np.ndarray]) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def _record(arrays: dict[str, np.ndarray], kind: str, version: int) -> np.ndarray:
    """A record as the cache writes it, for these arrays (ssw.cachefile's own layout)."""
    return np.asarray(json.dumps({"kind": kind, "version": version, "arrays": {
        k: [list(a.shape), a.dtype.str] for k, a in arrays.items()}}))


def _rebuilt_from(tmp_path, fresh, which: str, content: bytes, match: str) -> None:
    """Put ``content`` in place of the fresh cache's ``which`` file: the scene must warn
    (``match``), give the fresh force bit for bit, and leave a good file in its place."""
    want, files = fresh
    cache = tmp_path / "cache"
    for rel, data in files.values():
        (cache / rel).parent.mkdir(parents=True, exist_ok=True)
        (cache / rel).write_bytes(data)
    rel = files[which][0]
    (cache / rel).write_bytes(content)
    if which == "model":  # read when the layout or an operator is built from it
        (cache / files["layout"][0]).unlink()
    with pytest.warns(CacheWarning, match=match):
        got = _force(cache)
    np.testing.assert_array_equal(got, want)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        dims = ({"dofs": len(_members(files[which][1])["S"])} if FILES[which] is
                ops.BODY_FORMAT else None)
        assert cachefile.read_arrays(cache / rel, FILES[which], dims) is not None
        assert _members((cache / rel).read_bytes()).keys() == _members(files[which][1]).keys()


@pytest.mark.parametrize("which", sorted(FILES))
def test_a_file_of_an_older_format_is_rebuilt(tmp_path, fresh, which):
    """Format 1 (no record: the arrays alone), and a record of another version."""
    arrays = _members(fresh[1][which][1])
    record = json.loads(str(arrays.pop(cachefile.RECORD)))
    _rebuilt_from(tmp_path, fresh, which, _npz(arrays), "older format")
    other = {**arrays, cachefile.RECORD: _record(arrays, record["kind"], ops.FORMAT - 1)}
    _rebuilt_from(tmp_path, fresh, which, _npz(other), f"format version {ops.FORMAT - 1}")


@pytest.mark.parametrize("which", sorted(FILES))
def test_a_file_missing_an_array_is_rebuilt(tmp_path, fresh, which):
    """Each array left out, the record listing it (promised, missing) or not (written by a
    writer that forgot it)."""
    arrays = _members(fresh[1][which][1])
    record = arrays.pop(cachefile.RECORD)
    kind = FILES[which].kind
    for name in arrays:
        rest = {k: v for k, v in arrays.items() if k != name}
        _rebuilt_from(tmp_path, fresh, which, _npz({**rest, cachefile.RECORD: record}),
                      f"array '{name}' it promises is missing")
        own = _record(rest, kind, ops.FORMAT)
        _rebuilt_from(tmp_path, fresh, which, _npz({**rest, cachefile.RECORD: own}),
                      f"array '{name}' is missing")


def _reshaped(a: np.ndarray) -> np.ndarray:
    """``a`` one entry shorter along its first axis (a scalar: an array of one)."""
    return a.reshape(1) if a.ndim == 0 else a[:-1]


@pytest.mark.parametrize("which", sorted(FILES))
def test_a_file_holding_an_array_of_another_shape_is_rebuilt(tmp_path, fresh, which):
    """Each array one entry shorter: with the record it had (the file altered after it was
    written), and with a record that promises the new shape (a file consistent with itself
    whose shapes do not fit each other or the geometry: the operator of another mesh)."""
    arrays = _members(fresh[1][which][1])
    record = arrays.pop(cachefile.RECORD)
    kind = FILES[which].kind
    for name, a in arrays.items():
        bad = {**arrays, name: _reshaped(a)}
        _rebuilt_from(tmp_path, fresh, which, _npz({**bad, cachefile.RECORD: record}),
                      f"array '{name}' has shape .* the file promises")
        own = _record(bad, kind, ops.FORMAT)
        _rebuilt_from(tmp_path, fresh, which, _npz({**bad, cachefile.RECORD: own}),
                      "has shape|is [0-9]+, the caller expects")


def test_an_operator_of_another_size_than_its_geometry_needs_is_rebuilt(tmp_path, fresh):
    """The soil's operator replaced by one of its own leading block, with its own record:
    a consistent file, but of another size than the layout's interface dofs."""
    arrays = _members(fresh[1]["soil"][1])
    arrays.pop(cachefile.RECORD)
    n = len(arrays["S"])
    small = {**arrays, "S": np.ascontiguousarray(arrays["S"][:-1, :-1])}
    content = _npz({**small, cachefile.RECORD: _record(small, "contact.body", ops.FORMAT)})
    _rebuilt_from(tmp_path, fresh, "soil", content,
                  rf"array 'S' has shape \({n - 1}, {n - 1}\): axis 0 \(dofs\) is {n - 1}, "
                  rf"elsewhere {n}")


def test_a_writer_cannot_write_arrays_its_format_does_not_hold(tmp_path):
    with pytest.raises(ValueError, match="array 'S' has shape"):
        cachefile.write_arrays(tmp_path / "x.npz", ops.BODY_FORMAT,
                               {"S": np.zeros((2, 3)), "stats": "{}"})
    assert not list(tmp_path.iterdir())


def test_concurrent_builds_of_one_operator_both_succeed(tmp_path):
    """Two processes build the same operators into one empty cache at the same time: both
    finish with the same curve and every file left is complete (no temporary file)."""
    cache = tmp_path / "cache"
    code = textwrap.dedent(f"""
        import sys, numpy as np
        from pathlib import Path
        from ssw.contact.operators import OperatorStore
        from ssw.contact.scene import solve_curve
        c, _ = solve_curve(*{SCENE!r}, {CONTACT!r}, OperatorStore(Path({str(cache)!r})))
        np.save(sys.argv[1], c.force)
    """)
    procs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path / f"f{i}.npy")])
             for i in range(2)]
    assert [p.wait(timeout=300) for p in procs] == [0, 0]
    a, b = (np.load(tmp_path / f"f{i}.npy") for i in range(2))
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, _force(cache))
    assert not [p for p in cache.rglob("*") if p.name.endswith(".part")]


def test_the_cache_key_covers_the_source_that_computes_operators():
    """Derived from the package: the operators module's import closure holds the mesh, the
    assembly (surface weights included), the elements and the substructuring."""
    from ssw.provenance import module_closure

    names = {p.name for p in module_closure(["ssw.contact.operators"], packages=False)}
    assert {"operators.py", "mesh.py", "assembly.py", "elements.py",
            "substructure.py"} <= names
    import ssw.contact.assembly as asm

    assert hasattr(asm, "top_surface_weights")  # the weights live where the key sees them


def test_a_mesh_read_back_is_the_mesh_itself(tmp_path, monkeypatch):
    """A store that finds a geometry's mesh in the cache meshes nothing and holds every
    array of a fresh meshing, bit for bit and of the same type (its operators' stresses
    need it: ssw.contact.stress)."""
    from dataclasses import fields

    import ssw.contact.operators as ops
    from ssw.contact.scene import indentation_steps, settings_of

    cfg = settings_of(CONTACT)
    delta_end = float(indentation_steps(float(cfg["delta_max"]), int(cfg["steps"]),
                                        cfg.get("delta_reach"))[-1])
    geom = ops.geometry_of(cfg, SCENE[2], SCENE[3], delta_end, cfg["interface"])
    want = OperatorStore(None)._model(geom)  # meshed
    _force(tmp_path)
    assert (tmp_path / geom.key() / "model.npz").is_file()
    monkeypatch.setattr(ops, "build_mesh", lambda *a, **k: pytest.fail("meshed again"))
    got = OperatorStore(tmp_path)._model(geom)
    pairs = [(f"mesh.{f.name}", getattr(want.mesh, f.name), getattr(got.mesh, f.name))
             for f in fields(want.mesh)]
    pairs += [(f"layout.{f.name}", getattr(want.layout, f.name), getattr(got.layout, f.name))
              for f in fields(want.layout)]
    pairs += [(k, getattr(want, k), getattr(got, k)) for k in ("body", *ops._MODEL_ARRAYS)]
    for name, a, b in pairs:
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        else:
            assert type(a) is type(b) and a == b, name

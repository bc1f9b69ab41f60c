"""The operator cache cannot poison a study: a truncated or corrupt file is rebuilt and the
numbers are those of a fresh build; concurrent jobs writing the same operator both succeed
and leave a complete file; the cache key covers the source that computes the operators."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

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

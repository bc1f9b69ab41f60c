"""The device design at scale: the pieces that make a candidate cheap give what the direct
computation gives.

* the noise's TOF gain of the peak picker (:func:`ssw.design.sampling.picker_gain`, the
  picker's exact derivative) equals central differences of the picker itself
  (:func:`ssw.signal.peaks.refine_peaks`), sample by sample;
* the route of the workflow and of Slurm (``--family``/``--part`` jobs, then ``--merge``)
  recommends what one run of the same question and size does, with the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest


def test_picker_gain_is_the_pickers_derivative():
    """picker_gain against central differences of refine_peaks (step 1e-6 of the peak:
    truncation error ~1e-12 of the gain, rounding ~1e-10); rows whose window is cut by the
    record's edge, and rows whose sample is no peak (gain 0: the picker's parabola is
    clipped or convex there) included."""
    from ssw.design.sampling import picker_gain
    from ssw.signal.peaks import HALF_WINDOW, UPSAMPLE, refine_peaks

    rng = np.random.default_rng(3)
    m, n_s = 24, 70
    t = (np.arange(n_s)[None, :] - 30 - rng.uniform(-3, 3, (m, 1))) / rng.uniform(1.5, 5, (m, 1))
    s = np.exp(-0.5 * t**2) * rng.uniform(1, 100, (m, 1)) + 0.01 * rng.normal(size=(m, n_s))
    c = np.argmax(s, axis=1)
    c[:3] = [10, 12, 60]  # off the peak; the last one's window cut by the end
    pos, _ = refine_peaks(s, c, UPSAMPLE)
    gain = picker_gain(s, c, pos)
    fd = np.zeros(m)
    for i in range(m):
        h = 1e-6 * abs(s[i, c[i]])
        grad = []
        for k in range(max(c[i] - HALF_WINDOW, 0), min(c[i] + HALF_WINDOW + 1, n_s)):
            up, down = s[i].copy(), s[i].copy()
            up[k] += h
            down[k] -= h
            p = refine_peaks(np.stack([up, down]), np.array([c[i], c[i]]), UPSAMPLE)[0]
            grad.append((p[0] - p[1]) / (2 * h))
        fd[i] = np.linalg.norm(grad)
    live = fd > 0
    assert live.sum() >= m - 3
    np.testing.assert_allclose(gain[live], fd[live], rtol=1e-6)
    assert np.all(gain[~live] == 0.0)


#: One family of two chains (a part each), two striker masses scanned: with ``--size 10``
#: the scan's 4 devices and a bounded search of 3 evaluations from the best device of each
#: chain (``sized``: every chain and plate searched, as the default space at 10^4 and 10^5).
SPLIT_SPACE = {"bead_materials": ["chrome_steel", "tungsten_carbide"],
               "bead_diameters": [9.525e-3], "beads": [12], "sensor_positions": [0.5],
               "plate_materials": ["pla"],
               "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 2},
               "drop_height": {"range": [2e-3, 8e-3], "scan": 1},
               "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
               "finalists": 1, "refine_evaluations": 2, "moduli": 2, "plate_yield_limit": 3.0}
KEY = ("bead_material", "bead_diameter", "beads", "sensor_index", "sensor_mass_ratio",
       "striker_mass_ratio", "drop_height", "plate_material", "plate_thickness")


def test_a_design_split_into_parts_and_merged_is_the_single_run(tmp_path):
    """The Slurm route (``--family D:MAT --part I/N`` jobs sized by the config's
    ``design.device.size``, then ``--merge``) against one ``ssw design --space device``
    run of the same question and ``--size``: the same devices
    evaluated, the same recommended device with the same numbers, and every device
    evaluated at the same time step with the same per-soil numbers (the parts' chains run
    in the batches of the single run; each part's best is also evaluated at its own step,
    so the other part's best differs in its step only)."""
    import json

    import yaml
    from conftest import run_device_design

    from ssw.cli import main
    from ssw.design.device_eval import ARRAYS
    from ssw.design.space import space_from_dict

    single = run_device_design(tmp_path, SPLIT_SPACE, "--size", "10")
    space = space_from_dict(single["space"], single["space"]["plate_diameter_ratio"])
    assert space.size == 4 and single["spec"]["finalists"] == 2
    assert len(single["searches"]) == 2  # each chain searched
    # the parts as the workflow runs them: the size from the config's design.device.size
    cfg = yaml.safe_load((tmp_path / "config.yaml").read_text())
    cfg["design"]["device"]["size"] = 10
    (tmp_path / "sized.yaml").write_text(yaml.safe_dump(cfg))
    common = ["design", "--space", "device", "--config", str(tmp_path / "sized.yaml"),
              "--calibration", "none", "--soil-E", "20e6:200e6", "--soil-nu", "0.3",
              "--soil-yield-limit", "50"]
    parts = []
    for i in range(2):
        parts.append(tmp_path / f"part{i}.json")
        assert main([*common, "--family", "9.525e-3:pla", "--part", f"{i}/2", "--output",
                     str(parts[i])]) == 0
    chains = [{c["bead_material"] for c in json.loads(p.read_text())["candidates"]
               if c["source"] == "scan"} for p in parts]
    assert chains == [{"chrome_steel"}, {"tungsten_carbide"}]  # one chain a part
    merged_path = tmp_path / "merged.json"
    assert main(["design", "--space", "device", "--config", str(tmp_path / "config.yaml"),
                 "--merge", *map(str, parts), "--output", str(merged_path)]) == 0
    merged = json.loads(merged_path.read_text())
    # each chain searched once, by the part that scans it (the base device by neither)
    starts = sorted(x["start"]["bead_material"] for x in merged["searches"])
    assert starts == sorted(x["start"]["bead_material"] for x in single["searches"])
    assert starts == ["chrome_steel", "tungsten_carbide"]
    assert merged["recommended"]["label"] == single["recommended"]["label"]
    assert merged["recommended"]["step"] == single["recommended"]["step"] == "own"
    for name in ("resolution", "sensitivity", "soil_yield_index", "plate_yield_index",
                 "bead_yield_index", "mass"):
        # equal up to the operators' condensation order in one process (~1e-12)
        assert merged["recommended"][name] == pytest.approx(single["recommended"][name],
                                                            rel=1e-9), name

    def rows(res):
        return {tuple(c[k] for k in KEY): c for c in res["candidates"]}

    ra, rb = rows(single), rows(merged)
    assert set(ra) == set(rb) and len(ra) >= 7  # the scan's 4, the searches', the base
    # the base device (a chain outside the space) evaluated, searched from by no part
    assert single["reference"] is not None and merged["reference"] is not None
    same = [k for k in ra if ra[k]["step"] == rb[k]["step"]]
    assert len(same) >= len(ra) - 1
    for k in same:
        for name in ARRAYS:
            np.testing.assert_allclose(rb[k][name], ra[k][name], rtol=1e-9, err_msg=name)


def test_stresses_skipped_only_where_the_ranking_cannot_use_them():
    """One chain's devices (the 20-200 MPa recommendation, 12 x 9.525 mm chrome steel on
    0.548 mm PLA, dropped from 4.47 mm to 50 mm, two strikers) evaluated with the stresses
    where needed and with all of them: the same dynamics; a device whose stresses were
    skipped breaks a hard limit known without them in the full evaluation too, and its
    merit is a lower bound of the full one; the stresses computed are the full run's; and
    the ranking's feasible devices and recommendation are the same."""
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config
    from ssw.design.device_eval import BEFORE_STRESSES, evaluate
    from ssw.design.device_search import merit, rank
    from ssw.design.device_spec import DeviceSpec
    from ssw.design.space import DevicePoint

    cfg = load_config("config/config.yaml")
    dev, mats = device_of(cfg), library(cfg)
    base = chain_params(dev, mats, **numerics_of(cfg))
    spec = DeviceSpec((20e6, 200e6), 0.3, moduli=3)
    pts = [DevicePoint("chrome_steel", 9.525e-3, 12, 6, 0.956, st, h, "pla", 5.48e-4,
                       2.475e-2) for st in (0.923, 3.0) for h in (4.47e-3, 1.5e-2, 5e-2)]
    items = [(p, p.params(base, mats)) for p in pts]
    contact = dict(cfg.get("contact", {}))
    lazy, full = (evaluate(items, spec, mats, contact, base.bead_radius,
                           dev.full_scale_force, all_stresses=a) for a in (False, True))
    skipped = [c.stresses_skipped != "" for c in lazy]
    assert any(skipped) and not all(skipped)
    assert not any(c.stresses_skipped for c in full)
    for a, b, s in zip(lazy, full, skipped, strict=True):
        np.testing.assert_array_equal(a.resolution_E, b.resolution_E)
        if s:
            assert np.all(np.isnan(a.soil_yield_E)) and np.isnan(a.plate_yield_index)
            assert any(b.violations[k] > 0 for k in BEFORE_STRESSES)
            assert not b.hard_feasible
            assert merit(a) <= merit(b)
        else:
            np.testing.assert_allclose(a.soil_von_mises_E, b.soil_von_mises_E, rtol=1e-9)
            np.testing.assert_allclose(a.plate_von_mises_E, b.plate_von_mises_E, rtol=1e-9)
            assert a.feasible == b.feasible and merit(a) == pytest.approx(merit(b), rel=1e-9)
    ra, rb = rank(lazy), rank(full)
    assert ra.recommended.key == rb.recommended.key
    assert {c.key for c in lazy if c.feasible} == {c.key for c in full if c.feasible}


def test_bench_times_the_sized_design_and_reports_its_recommendation(tmp_path):
    """``ssw bench design --space device --sizes N`` runs ``ssw design --space device
    --size N`` (:func:`ssw.bench.design.device_argv`): its row states that run's
    evaluations and recommended device, its CSV reads back (the device's label quoted)."""
    import csv
    import json
    from pathlib import Path

    import yaml

    from ssw.bench.design import device_argv
    from ssw.cli import main

    root = Path(__file__).resolve().parents[1]
    cfg = yaml.safe_load((root / "config" / "config.yaml").read_text())
    cfg["design"]["device"] = {**SPLIT_SPACE, "bead_materials": ["chrome_steel"]}
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    assert main(["bench", "design", "--space", "device", "--sizes", "6", "--jobs", "1",
                 "--config", str(config), "--output-dir", str(tmp_path / "bench")]) == 0
    direct = tmp_path / "direct.json"
    assert main([*device_argv(str(config), 6, 1), "--output", str(direct)]) == 0
    want = json.loads(direct.read_text())
    with open(tmp_path / "bench" / "design_device_bench.csv") as fh:
        (row,) = csv.DictReader(line for line in fh if not line.startswith("#"))
    assert row["recommended"] == want["recommended"]["label"] and "," in row["recommended"]
    assert int(row["candidates"]) == want["evaluations"]
    assert float(row["resolution"]) == pytest.approx(want["recommended"]["resolution"],
                                                     rel=1e-9)
    assert float(row["cpu_time"]) > 0 and float(row["wall_time"]) > 0

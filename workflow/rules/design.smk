# Plate design: for every soil range of config `design.soils`, which plate under the chain
# (material x continuous thickness) makes the device most sensitive to the soil's modulus
# while the plate stays elastic and the sample yields least. One job per range and
# material (`ssw design --soil-range R --materials M`: a bounded thickness search with the
# chain on the exact fem wall of each plate), then one table per range ranking the
# materials' candidates together (`ssw design --merge`).
# Science lives in ssw.design and ssw.contact.stress; these rules call `ssw design`.
#
# Outputs (results/design/):
#   {soil}/{material}.json          ssw design result of one material (candidates, search)
#   {soil}.json / {soil}.csv        the range's ranking: recommended plate, reasons, Pareto front
#   figures/{soil}_pareto.png       sensitivity against the sample's yield index; sensitivity curves

DESIGN_DIR = f"{RESULTS}/design"
DESIGN_SOILS = list(config.get("design", {}).get("soils", {}))
DESIGN_MATERIALS = list(config.get("design", {}).get("materials", []))


# One soil range, one plate material: the thickness search and its candidates. Input: with
# calibration.use, the calibration (the design's device is the calibrated one; the design
# runs the fem wall whatever the study's wall law).
rule design_material:
    input:
        unpack(
            lambda wc: {
                k: v
                for k, v in sswwf.calibrated_inputs(config, RESULTS).items()
                if k == "calibration"
            }
        ),
    output:
        json=f"{DESIGN_DIR}/{{soil}}/{{material}}.json",
    log:
        f"{LOGS}/design/{{soil}}_{{material}}.log",
    benchmark:
        f"{BENCHMARKS}/design/{{soil}}_{{material}}.tsv"
    wildcard_constraints:
        soil=sswwf.alternatives(DESIGN_SOILS),
        material=sswwf.alternatives(DESIGN_MATERIALS),
    # The longest jobs of a study with a design, on its critical path (calibration ->
    # design -> ranking): they start as soon as the calibration is there, before the sweep
    # (40) and the validation (30), which the remaining cores fit in around them.
    priority: 45
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("design", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("design", 0) * attempt,
    params:
        inputs=lambda wc: inputs_of("design", wc.soil),
        digest=lambda wc: digest_of("design", wc.soil),
        config=STUDY_CONFIG,
        calibration=lambda wc, input: sswwf.calibration_flag(input),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} design "
        "--soil-range {wildcards.soil:q} --materials {wildcards.material:q} "
        "--config {params.config:q} {params.calibration:q} --output {output.json:q} "
        "> {log:q} 2>&1"


# One soil range: every material's candidates ranked together, the table and the figure.
rule design_table:
    input:
        lambda wc: expand(
            f"{DESIGN_DIR}/{wc.soil}/{{material}}.json", material=DESIGN_MATERIALS
        ),
    output:
        json=f"{DESIGN_DIR}/{{soil}}.json",
        csv=report(
            f"{DESIGN_DIR}/{{soil}}.csv",
            caption="../report/design_table.rst",
            category=REPORT_CATEGORIES["design"],
            subcategory="Tables",
        ),
        plot=report(
            f"{DESIGN_DIR}/figures/{{soil}}_pareto.png",
            caption="../report/design_pareto.rst",
            category=REPORT_CATEGORIES["design"],
            subcategory="Figures",
        ),
    log:
        f"{LOGS}/design/{{soil}}_table.log",
    benchmark:
        f"{BENCHMARKS}/design/{{soil}}_table.tsv"
    wildcard_constraints:
        soil=sswwf.alternatives(DESIGN_SOILS),
    conda:
        SSW_ENV
    params:
        inputs=lambda wc: inputs_of("design_table", wc.soil),
        digest=lambda wc: digest_of("design_table", wc.soil),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} design --merge {input:q} "
        "--output {output.json:q} --csv {output.csv:q} --plot {output.plot:q} > {log:q} 2>&1"


DESIGN_TARGETS = expand(
    [
        f"{DESIGN_DIR}/{{soil}}.json",
        f"{DESIGN_DIR}/{{soil}}.csv",
        f"{DESIGN_DIR}/figures/{{soil}}_pareto.png",
    ],
    soil=DESIGN_SOILS,
)


# Device design (config design.device, on with design.device.study): for every soil range,
# the whole device (beads, sensor, striker, drop, plate) as the design variable. One job
# per bead diameter and plate material, its chains scattered over design.device.parts jobs
# (Snakemake's scattergather `device`):
# `ssw design --space device --family D:MAT --part I/N` scans part I's chains and searches
# its best devices at a mesh of its own bead radius. The table rule gathers every part of
# every family and ranks their devices together (`--merge`), then strikes the finalists
# (design.device.plastic_hits > 0) with the base device of the study's config.
#
# Outputs (results/design/device/):
#   {soil}/{family}/{i}-of-{n}.json  one part of one family's devices (scan, search, best)
#   {soil}.json / {soil}.csv         the range's ranking: recommended device, reasons, fronts
#   figures/{soil}_pareto.png        resolution against the sample's yield and the mass
DEVICE_DIR = f"{DESIGN_DIR}/device"
DEVICE_FAMILIES = STUDY.device_families()


scattergather:
    device=sswwf.device_parts(config),


rule design_device_family:
    input:
        unpack(device_calibration),
    output:
        json=f"{DEVICE_DIR}/{{soil}}/{{family}}/{{scatteritem}}.json",
    log:
        f"{LOGS}/design/device_{{soil}}_{{family}}_{{scatteritem}}.log",
    benchmark:
        f"{BENCHMARKS}/design/device_{{soil}}_{{family}}_{{scatteritem}}.tsv"
    wildcard_constraints:
        soil=sswwf.alternatives(DESIGN_SOILS),
        family=sswwf.alternatives(DEVICE_FAMILIES),
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("design_device", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("design_device", 0) * attempt,
    params:
        inputs=lambda wc: inputs_of("design_device", wc.soil),
        digest=lambda wc: digest_of("design_device", wc.soil),
        config=STUDY_CONFIG,
        calibration=lambda wc, input: sswwf.calibration_flag(input),
        family=lambda wc: DEVICE_FAMILIES[wc.family],
        part=lambda wc: sswwf.scatter_part(wc.scatteritem),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} design --space device "
        "--soil-range {wildcards.soil:q} --family {params.family:q} --part {params.part:q} "
        "--config {params.config:q} {params.calibration:q} --output {output.json:q} "
        "> {log:q} 2>&1"


rule design_device_table:
    input:
        unpack(
            lambda wc: {
                "parts": gather.device(
                    f"{DEVICE_DIR}/{wc.soil}/{{family}}/{{scatteritem}}.json",
                    family=DEVICE_FAMILIES,
                ),
                **device_calibration(wc),
            }
        ),
    output:
        json=f"{DEVICE_DIR}/{{soil}}.json",
        csv=report(
            f"{DEVICE_DIR}/{{soil}}.csv",
            caption="../report/design_device.rst",
            category=REPORT_CATEGORIES["design"],
            subcategory="Device",
        ),
        plot=report(
            f"{DEVICE_DIR}/figures/{{soil}}_pareto.png",
            caption="../report/design_device.rst",
            category=REPORT_CATEGORIES["design"],
            subcategory="Device",
        ),
    log:
        f"{LOGS}/design/device_{{soil}}_table.log",
    wildcard_constraints:
        soil=sswwf.alternatives(DESIGN_SOILS),
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("design_device", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("design_device", 0) * attempt,
    params:
        inputs=lambda wc: inputs_of("design_device_table", wc.soil),
        digest=lambda wc: digest_of("design_device_table", wc.soil),
        config=STUDY_CONFIG,
        calibration=lambda wc, input: sswwf.calibration_flag(input),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} design --space device "
        "--merge {input.parts:q} --config {params.config:q} {params.calibration:q} "
        "--output {output.json:q} --csv {output.csv:q} --plot {output.plot:q} > {log:q} 2>&1"


DESIGN_TARGETS += (
    expand(
        [
            f"{DEVICE_DIR}/{{soil}}.json",
            f"{DEVICE_DIR}/{{soil}}.csv",
            f"{DEVICE_DIR}/figures/{{soil}}_pareto.png",
        ],
        soil=DESIGN_SOILS,
    )
    if DEVICE_FAMILIES
    else []
)

# Stage II: the device's calibration on MEASURED TOFs, and the chain dynamics: the TOF(E, nu)
# sweep (thesis Fig 8) in scatter parts (Snakefile `scattergather: sweep`; more parts for a
# cluster: --set-scatter sweep=N), gathered into one table and figure.
# Science lives in ssw.calibration and ssw.chain; these rules call `ssw calibrate`,
# `ssw tof-sweep` and `ssw tof-merge`; input helpers are in ssw.workflow.
#
# Outputs:
#   results/calibration/calibration.json  the calibrated device: the config's calibration.free
#                                  parameters identified from the validation samples'
#                                  measured TOFs (recordings, else the published means), with
#                                  standard errors, singular values, residuals, leave-one-out
#                                  (read by the sweep, the validation and `ssw ... --calibration`)
#   results/calibration/summary.json      the same as `ssw calibrate --json` prints
#   results/chain/parts/tof_{i}-of-{n}.h5 one interleaved share of the sweep points per job
#   results/chain/tof_sweep.h5 / .csv     every sweep point: soil_E (Pa), soil_nu, tof (s), peaks
#   results/chain/figures/fig8_tof_vs_E.png  Fig 8 style: TOF vs E, one line per nu

CHAIN_DIR = f"{RESULTS}/chain"


# The free parameters of the device, identified from the measured TOFs of the samples.
rule calibration:
    input:
        unpack(lambda wc: sswwf.wall_inputs(config, RESULTS)),
        recordings=sswwf.recordings(config, RECORDINGS_ROOT),
    output:
        cal=f"{RESULTS}/{sswwf.CALIBRATION}",
        json=f"{RESULTS}/calibration/summary.json",
    log:
        f"{LOGS}/calibration/calibration.log",
    benchmark:
        f"{BENCHMARKS}/calibration/calibration.tsv"
    # the study's critical path (calibration -> sweep -> validation) goes first
    priority: 50
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("calibration", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("calibration", 0) * attempt,
    params:
        inputs=inputs_of("calibration"),
        digest=digest_of("calibration"),
        config=STUDY_CONFIG,
        root=RECORDINGS_ROOT,
        wall=lambda wc, input: sswwf.wall_flags(config, input, RESULTS),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} calibrate --from-config "
        "--config {params.config:q} {params.wall:q} --root {params.root:q} "
        "--calibration none --output {output.cal:q} --json > {output.json:q} 2> {log:q}"


# One interleaved part of the TOF sweep, batched; with resources `tasks` > 1 its ranks
# share the part under MPI (`mpiexec`, or the launcher of the cluster: resources `mpi`).
rule tof_sweep:
    input:
        unpack(calibrated_inputs),
    output:
        f"{CHAIN_DIR}/parts/tof_{{scatteritem}}.h5",
    log:
        f"{LOGS}/chain/tof_{{scatteritem}}.log",
    benchmark:
        f"{BENCHMARKS}/chain/tof_{{scatteritem}}.tsv"
    wildcard_constraints:
        scatteritem=r"\d+-of-\d+",
    priority: 40
    conda:
        SSW_ENV
    threads: 1
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("sweep", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("sweep", 0) * attempt,
        tasks=1,
    params:
        inputs=inputs_of("sweep"),
        digest=digest_of("sweep"),
        config=STUDY_CONFIG,
        chain=chain_flags,
        launch=lambda wc, resources: sswwf.mpi_launch(resources),
        mpi=lambda wc, resources: sswwf.mpi_flag(resources),
    shell:
        "{params.launch:q} python -m ssw --inputs-sha256 {params.digest:q} tof-sweep "
        "--config {params.config:q} {params.chain:q} {params.mpi:q} "
        "--part {wildcards.scatteritem:q} --output {output:q} > {log:q} 2>&1"


# The parts of the sweep merged: one table, its CSV and the Fig 8 style plot.
rule sweep_figure:
    input:
        gather.sweep(f"{CHAIN_DIR}/parts/tof_{{scatteritem}}.h5"),
    output:
        h5=f"{CHAIN_DIR}/tof_sweep.h5",
        csv=f"{CHAIN_DIR}/tof_sweep.csv",
        fig8=report(
            f"{CHAIN_DIR}/figures/fig8_tof_vs_E.png",
            caption="../report/fig8.rst",
            category=REPORT_CATEGORIES["chain"],
            subcategory="Figures",
        ),
    log:
        f"{LOGS}/chain/tof_sweep.log",
    benchmark:
        f"{BENCHMARKS}/chain/sweep_figure.tsv"
    conda:
        SSW_ENV
    params:
        inputs=inputs_of("sweep_figure"),
        digest=digest_of("sweep_figure"),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} tof-merge {input:q} "
        "--output {output.h5:q} --csv {output.csv:q} --plot {output.fig8:q} > {log:q} 2>&1"


CHAIN_TARGETS = [
    *rules.sweep_figure.output,
    *(rules.calibration.output if sswwf.uses_calibration(config) else []),
]

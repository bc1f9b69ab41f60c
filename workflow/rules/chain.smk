# Stage II: chain dynamics. TOF(E, nu) sweep (thesis Fig 8) split into chain.sweep.chunks
# jobs, merged; the striker speed calibration on PCF 30. (What a fitted law's error costs in
# TOF, against the FEM curve itself, is the fit stage's rule fit_tof_impact.)
# Science lives in ssw.chain; these rules call `ssw tof-sweep`, `ssw tof-merge` and
# `ssw tof-calibrate`; input helpers are ssw.chain.workflow.
#
# Outputs (results/chain/):
#   chunks/tof_{chunk}.h5          one interleaved share of the sweep points per job
#   tof_sweep.h5 / .csv            every sweep point: soil_E (Pa), soil_nu, tof (s), peaks
#   figures/fig8_tof_vs_E.png      Fig 8 style: TOF vs E, one line per nu
#   calibration.json               striker speed calibrated on PCF 30 with the config's wall
#                                  law, and the PCF 08/15 predictions (thesis Table 2); the
#                                  config's chain.striker_velocity is the Hertz-wall value (a
#                                  fit-wall value would be circular: the fit range depends on it)


CHAIN_DIR = f"{RESULTS}/chain"
CHAIN_CHUNKS = int(config["chain"]["sweep"].get("chunks", 1))
CHAIN_RANKS = int(config["chain"]["sweep"].get("mpi_ranks", 1))


rule tof_sweep_chunk:
    """One interleaved chunk of the TOF sweep, batched (MPI ranks if chain.sweep.mpi_ranks > 1)."""
    input:
        unpack(lambda wc: chainwf.calibrated_inputs(config, RESULTS)),
    output:
        h5=f"{CHAIN_DIR}/chunks/tof_{{chunk}}.h5",
        json=f"{CHAIN_DIR}/chunks/tof_{{chunk}}.json",
    log:
        f"{LOGS}/chain/tof_{{chunk}}.log",
    threads: CHAIN_RANKS
    params:
        config=CONFIG_FILE,
        chunks=CHAIN_CHUNKS,
        wall=lambda wc, input: chainwf.wall_flags(config, input, RESULTS),
        calibration=lambda wc, input: chainwf.calibration_flag(input),
        launch=f"mpiexec -n {CHAIN_RANKS} " if CHAIN_RANKS > 1 else "",
        mpi="--mpi" if CHAIN_RANKS > 1 else "",
    wildcard_constraints:
        chunk=r"\d+",
    conda:
        SSW_ENV
    shell:
        "{params.launch}python -m ssw tof-sweep --config {params.config} {params.wall} {params.mpi} "
        "{params.calibration} "
        "--chunk {wildcards.chunk} --chunks {params.chunks} --output {output.h5} "
        "--json > {output.json} 2> {log}"


rule tof_sweep:
    """Merge the chunks; CSV and the Fig 8 style plot."""
    input:
        expand(f"{CHAIN_DIR}/chunks/tof_{{chunk}}.h5", chunk=range(CHAIN_CHUNKS)),
    output:
        h5=f"{CHAIN_DIR}/tof_sweep.h5",
        csv=f"{CHAIN_DIR}/tof_sweep.csv",
        fig8=f"{CHAIN_DIR}/figures/fig8_tof_vs_E.png",
    log:
        f"{LOGS}/chain/tof_sweep.log",
    conda:
        SSW_ENV
    shell:
        "python -m ssw tof-merge {input} --output {output.h5} --csv {output.csv} --plot {output.fig8} "
        "> {log} 2>&1"


rule tof_calibration:
    """Striker speed calibrated on PCF 30 with the config's wall law; PCF 08/15 predicted."""
    input:
        unpack(lambda wc: chainwf.wall_inputs(config, RESULTS)),
    output:
        json=f"{RESULTS}/{chainwf.CALIBRATION}",
    log:
        f"{LOGS}/chain/calibration.log",
    params:
        config=CONFIG_FILE,
        wall=lambda wc, input: chainwf.wall_flags(config, input, RESULTS),
    conda:
        SSW_ENV
    shell:
        "python -m ssw tof-calibrate --config {params.config} {params.wall} --foam PCF30 --json "
        "> {output.json} 2> {log}"


CHAIN_TARGETS = [
    rules.tof_sweep.output.h5,
    rules.tof_sweep.output.csv,
    rules.tof_sweep.output.fig8,
    rules.tof_calibration.output.json,
]

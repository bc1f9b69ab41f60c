# Stage II: the device's calibration on MEASURED TOFs, and the chain dynamics: TOF(E, nu)
# sweep (thesis Fig 8) split into chain.sweep.chunks jobs, merged. (What a fitted law's error
# costs in TOF, against the FEM law itself, is the fit stage's rule fit_tof_impact.)
# Science lives in ssw.calibration and ssw.chain; these rules call `ssw calibrate`,
# `ssw tof-sweep` and `ssw tof-merge`; input helpers are ssw.chain.workflow.
#
# Outputs:
#   results/calibration/calibration.json  the calibrated device: the config's calibration.free
#                                  parameters identified from the validation samples'
#                                  measured TOFs (recordings, else the published means), with
#                                  standard errors, singular values, residuals, leave-one-out
#                                  (read by the sweep, the validation and `ssw ... --calibration`)
#   results/calibration/summary.json      the same as `ssw calibrate --json` prints
#   results/chain/chunks/tof_{chunk}.h5   one interleaved share of the sweep points per job
#                                         (chain.sweep.chunks > 1; one job writes it all else)
#   results/chain/tof_sweep.h5 / .csv     every sweep point: soil_E (Pa), soil_nu, tof (s), peaks
#   results/chain/figures/fig8_tof_vs_E.png  Fig 8 style: TOF vs E, one line per nu


CHAIN_DIR = f"{RESULTS}/chain"
CHAIN_CHUNKS = int(config["chain"]["sweep"].get("chunks", 1))
CHAIN_RANKS = int(config["chain"]["sweep"].get("mpi_ranks", 1))


FIG8 = report(
    f"{CHAIN_DIR}/figures/fig8_tof_vs_E.png",
    caption="../report/fig8.rst",
    category="3. Chain (Stage II)",
    subcategory="Figures",
)


if CHAIN_CHUNKS == 1:

    rule tof_sweep:
        """The whole TOF sweep in one job (batched; MPI ranks if chain.sweep.mpi_ranks > 1),
        its CSV and the Fig 8 style plot."""
        priority: 40
        input:
            unpack(lambda wc: chainwf.calibrated_inputs(config, RESULTS)),
        output:
            h5=f"{CHAIN_DIR}/tof_sweep.h5",
            csv=f"{CHAIN_DIR}/tof_sweep.csv",
            fig8=FIG8,
            json=f"{CHAIN_DIR}/tof_sweep.json",
        log:
            f"{LOGS}/chain/tof_sweep.log",
        threads: CHAIN_RANKS
        params:
            config=CONFIG_FILE,
            wall=lambda wc, input: chainwf.wall_flags(config, input, RESULTS),
            calibration=lambda wc, input: chainwf.calibration_flag(input),
            launch=f"mpiexec -n {CHAIN_RANKS} " if CHAIN_RANKS > 1 else "",
            mpi="--mpi" if CHAIN_RANKS > 1 else "",
        conda:
            SSW_ENV
        shell:
            "{params.launch}python -m ssw tof-sweep --config {params.config} {params.wall} "
            "{params.mpi} {params.calibration} --output {output.h5} --csv {output.csv} "
            "--plot {output.fig8} --json > {output.json} 2> {log}"

else:

    rule tof_sweep_chunk:
        """One interleaved chunk of the TOF sweep, batched (MPI ranks if
        chain.sweep.mpi_ranks > 1)."""
        priority: 40
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
            "{params.launch}python -m ssw tof-sweep --config {params.config} {params.wall} "
            "{params.mpi} {params.calibration} "
            "--chunk {wildcards.chunk} --chunks {params.chunks} --output {output.h5} "
            "--json > {output.json} 2> {log}"

    rule tof_sweep:
        """Merge the chunks; CSV and the Fig 8 style plot."""
        priority: 40
        input:
            expand(f"{CHAIN_DIR}/chunks/tof_{{chunk}}.h5", chunk=range(CHAIN_CHUNKS)),
        output:
            h5=f"{CHAIN_DIR}/tof_sweep.h5",
            csv=f"{CHAIN_DIR}/tof_sweep.csv",
            fig8=FIG8,
        log:
            f"{LOGS}/chain/tof_sweep.log",
        conda:
            SSW_ENV
        shell:
            "python -m ssw tof-merge {input} --output {output.h5} --csv {output.csv} "
            "--plot {output.fig8} > {log} 2>&1"


rule calibration:
    """The device's free parameters identified from the validation samples' measured TOFs."""
    # the study's critical path (calibration -> sweep -> validation) goes first
    priority: 50
    input:
        unpack(lambda wc: chainwf.wall_inputs(config, RESULTS)),
        recordings=chainwf.recordings(config, RECORDINGS_ROOT),
    output:
        cal=f"{RESULTS}/{chainwf.CALIBRATION}",
        json=f"{RESULTS}/calibration/summary.json",
    log:
        f"{LOGS}/calibration/calibration.log",
    params:
        config=CONFIG_FILE,
        wall=lambda wc, input: chainwf.wall_flags(config, input, RESULTS),
        root=RECORDINGS_ROOT,
    conda:
        SSW_ENV
    shell:
        "python -m ssw calibrate --from-config --config {params.config} {params.wall} "
        "--root {params.root} --calibration none --output {output.cal} --json "
        "> {output.json} 2> {log}"


CHAIN_TARGETS = [
    rules.tof_sweep.output.h5,
    rules.tof_sweep.output.csv,
    rules.tof_sweep.output.fig8,
    *(rules.calibration.output if chainwf.uses_calibration(config) else []),
]

# Stage I fits: modified-Hertz laws per contact scene, aggregated into K(E, nu) tables.
# Science lives in ssw.fit; these rules call the `ssw fit-*` commands.
#
# Outputs (results/fit/):
#   k_table.h5 / .csv / .json     the table of the set `fit.set`, read by the chain stage
#   sets/{set}/k_table.h5 / .csv  per-set tables (every set of the config)
#   deviation_{set}.csv           deviation from Hertz at fit.delta_ref, next to the thesis
#                                 (sets with one soil: the thesis's Sets 1 and 2)
#   figures/{set}_curves.png      force vs indentation with bare-soil Hertz (Figs 5, 6)
#   figures/{set}_deviation.png   deviation from Hertz per scene (Figs 5, 6 statements)
#   figures/{set}_k_vs_E.png      K vs soil E for each nu (Fig 7; sets with several soils)
#   tof_impact_{set}.csv          TOF with the curve itself vs the K and power fits (grid sets)


ONE_SOIL_SETS = [s for s in config["sets"] if _n_soils(s) == 1]
GRID_SETS = [s for s in config["sets"] if _n_soils(s) > 1]


rule k_table:
    """The K(E, nu) table the chain stage consumes (set `fit.set`)."""
    input:
        curves=lambda wc: contact_curves(config["fit"]["set"]),
    output:
        h5=f"{RESULTS}/fit/k_table.h5",
        csv=f"{RESULTS}/fit/k_table.csv",
        json=f"{RESULTS}/fit/k_table.json",
    log:
        f"{LOGS}/fit/k_table.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-table {input.curves} --output {output.h5} --csv {output.csv} "
        "--config {params.config} --json > {output.json} 2> {log}"


rule fit_set_table:
    """Fits of every scene of one set, as a table (one group per plate)."""
    input:
        curves=lambda wc: contact_curves(wc.set),
    output:
        h5=f"{RESULTS}/fit/sets/{{set}}/k_table.h5",
        csv=f"{RESULTS}/fit/sets/{{set}}/k_table.csv",
        json=f"{RESULTS}/fit/sets/{{set}}/k_table.json",
    log:
        f"{LOGS}/fit/sets/{{set}}.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-table {input.curves} --output {output.h5} --csv {output.csv} "
        "--config {params.config} --json > {output.json} 2> {log}"


rule fit_deviation:
    """Deviation from Hertz at fit.delta_ref for a one-soil set, with the thesis's values."""
    input:
        curves=lambda wc: contact_curves(wc.set),
    output:
        csv=f"{RESULTS}/fit/deviation_{{set}}.csv",
        json=f"{RESULTS}/fit/deviation_{{set}}.json",
    log:
        f"{LOGS}/fit/deviation_{{set}}.log",
    params:
        config=CONFIG_FILE,
        kind=lambda wc: deviation_kind(wc.set),
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-deviation {input.curves} --set-kind {params.kind} --output {output.csv} "
        "--config {params.config} --json > {output.json} 2> {log}"


rule fit_figure_curves:
    """Force vs indentation of a set's scenes with their bare-soil Hertz laws."""
    input:
        curves=lambda wc: contact_curves(wc.set),
    output:
        f"{RESULTS}/fit/figures/{{set}}_curves.png",
    log:
        f"{LOGS}/fit/figures/{{set}}_curves.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-plot curves {input.curves} --output {output} --title {wildcards.set} "
        "--config {params.config} > {log} 2>&1"


rule fit_figure_deviation:
    """Deviation from Hertz per scene of a one-soil set (thesis Figs 5 and 6)."""
    input:
        curves=lambda wc: contact_curves(wc.set),
    output:
        f"{RESULTS}/fit/figures/{{set}}_deviation.png",
    log:
        f"{LOGS}/fit/figures/{{set}}_deviation.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-plot deviation {input.curves} --output {output} --title {wildcards.set} "
        "--config {params.config} > {log} 2>&1"


rule fit_figure_k:
    """K vs soil E for each nu with the interpolant and the fits' residuals (thesis Fig 7)."""
    input:
        rules.fit_set_table.output.h5,
    output:
        f"{RESULTS}/fit/figures/{{set}}_k_vs_E.png",
    log:
        f"{LOGS}/fit/figures/{{set}}_k_vs_E.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-plot k {input} --output {output} --config {params.config} > {log} 2>&1"


rule fit_tof_impact:
    """TOF with the FEM curve itself vs the fitted K and (C, n) laws: what fit error costs."""
    input:
        curves=lambda wc: contact_curves(wc.set),
    output:
        csv=f"{RESULTS}/fit/tof_impact_{{set}}.csv",
        json=f"{RESULTS}/fit/tof_impact_{{set}}.json",
    log:
        f"{LOGS}/fit/tof_impact_{{set}}.log",
    params:
        config=CONFIG_FILE,
    conda:
        SSW_ENV
    shell:
        "python -m ssw fit-tof-impact {input.curves} --output {output.csv} --config {params.config} "
        "--json > {output.json} 2> {log}"


FIT_TARGETS = (
    ([rules.k_table.output.h5] if config["fit"].get("set") else [])
    + expand(rules.fit_set_table.output.h5, set=list(config["sets"]))
    + expand(rules.fit_deviation.output.csv, set=ONE_SOIL_SETS)
    + expand(rules.fit_figure_curves.output, set=ONE_SOIL_SETS)
    + expand(rules.fit_figure_deviation.output, set=ONE_SOIL_SETS)
    + expand(rules.fit_figure_k.output, set=GRID_SETS)
    + expand(rules.fit_tof_impact.output.csv, set=GRID_SETS)
)

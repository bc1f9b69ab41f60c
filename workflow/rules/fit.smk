# Stage I fits: modified-Hertz laws per contact scene, aggregated into K(E, nu) tables; the
# thesis's reports (Figs 5-7) and what each fitted law costs in TOF. One job per set: a
# set's outputs come from one `ssw fit-set` process (imports paid once; the fits are cheap).
# Science lives in ssw.fit.
#
# Outputs (results/fit/):
#   sets/{set}/k_table.h5 / .csv / .json   every law's fit of every scene of the set
#   k_table.h5 / .csv / .json     the table of the set `fit.set` (the chain's `fit` wall)
#   deviation_{set}.csv / .json   deviation from Hertz at fit.delta_ref, next to the thesis
#                                 (sets with one soil: the thesis's Sets 1 and 2)
#   figures/{set}_curves.png      force vs indentation with bare-soil Hertz (Figs 5, 6)
#   figures/{set}_deviation.png   deviation from Hertz per scene (Figs 5, 6 statements)
#   figures/{set}_k_vs_E.png      K vs soil E for each nu (Fig 7; sets with several soils)
#   tof_impact_{set}.csv / .json  TOF with the FEM law itself vs the K and power fits


ONE_SOIL_SETS = [s for s in config["sets"] if _n_soils(s) == 1]
GRID_SETS = [s for s in config["sets"] if _n_soils(s) > 1]
FIT_DIR = f"{RESULTS}/fit"
# figure name ending -> its caption in workflow/report/ (the Snakemake report)
FIT_FIGURE_CAPTIONS = {
    "_curves.png": "../report/fit_curves.rst",
    "_deviation.png": "../report/fit_deviation.rst",
    "_k_vs_E.png": "../report/fit_k_vs_E.rst",
}


def fit_set_outputs(set_name):
    """The files `ssw fit-set` writes for one set (ssw.cli.fit.run_set)."""
    out = [f"{FIT_DIR}/sets/{set_name}/k_table.{ext}" for ext in ("h5", "csv", "json")]
    if set_name == config["fit"].get("set"):
        out += [f"{FIT_DIR}/k_table.{ext}" for ext in ("h5", "csv", "json")]
    if set_name in ONE_SOIL_SETS:
        out += [f"{FIT_DIR}/deviation_{set_name}.csv", f"{FIT_DIR}/deviation_{set_name}.json",
                f"{FIT_DIR}/figures/{set_name}_curves.png",
                f"{FIT_DIR}/figures/{set_name}_deviation.png"]
    else:
        out += [f"{FIT_DIR}/figures/{set_name}_k_vs_E.png",
                f"{FIT_DIR}/tof_impact_{set_name}.csv", f"{FIT_DIR}/tof_impact_{set_name}.json"]
    return out


def contact_figure(set_name):
    """The set's contact figure (thesis Figs 5, 6: contact.smk's CONTACT_FIGURES), or None."""
    spec = CONTACT_FIGURES.get(set_name)
    return f"{RESULTS}/contact/figures/{spec[0]}.png" if spec else None


def contact_figure_flags(set_name):
    """`ssw fit-set` flags that also draw the set's contact figure."""
    if set_name not in CONTACT_FIGURES:
        return ""
    _, label_by, title = CONTACT_FIGURES[set_name]
    return (f"--contact-figure {contact_figure(set_name)} --label-by {label_by} "
            f"--title '{title}'")


for _set in config["sets"]:

    # every fit output of one set, one process
    rule:
        name:
            f"fit_set_{_set}"
        input:
            contact_curves(_set),
        output:
            [
                report(f, caption=cap, category="2. Fits (Stage I)", subcategory="Figures")
                if (cap := next((c for e, c in FIT_FIGURE_CAPTIONS.items() if f.endswith(e)), None))
                else f
                for f in fit_set_outputs(_set)
            ]
            + (
                [
                    report(
                        contact_figure(_set),
                        caption="../report/contact_figure.rst",
                        category="1. Contact (Stage I)",
                        subcategory="Figures",
                    )
                ]
                if contact_figure(_set)
                else []
            ),
        log:
            f"{LOGS}/fit/{_set}.log",
        # on a cluster, the fits join the cheap figure jobs in one submission (the slurm
        # profile's group "figures"); a local run ignores groups
        group:
            "figures"
        params:
            config=CONFIG_FILE,
            set=_set,
            # results/fit: three levels above sets/{set}/k_table.h5
            outdir=lambda wildcards, output: os.path.dirname(
                os.path.dirname(os.path.dirname(output[0]))
            ),
            figure=contact_figure_flags(_set),
        conda:
            SSW_ENV
        shell:
            "python -m ssw fit-set {params.set} {input} --outdir {params.outdir} "
            "{params.figure} --config {params.config} > {log} 2>&1"


FIT_TARGETS = [f for s in config["sets"] for f in fit_set_outputs(s)] + [
    f for s in config["sets"] if (f := contact_figure(s))
]

# Survey studies: the modulus of every test point of config `survey.points` (ssw measure,
# one job per point, through the study's calibrated device), gathered into a table with
# pass/fail/inconclusive verdicts against each point's target, and its figures.
# Science lives in ssw.measure and ssw.survey; these rules call `ssw measure` and
# `ssw survey-table`.
#
# Outputs (results/survey/):
#   points/{point}.json            ssw measure --json of one point (E, E_low, E_high, budget)
#   survey.csv / survey.h5         one row per point: E, interval, target, verdict, coordinates
#   figures/survey_E.png           E per point with its 95 % interval against its target
#   figures/survey_map.png         plan view (only when the points have coordinates)
#   survey.geojson                 the points for a GIS (only when they have coordinates):
#                                  WGS84 lon/lat, else the local x/y of survey.frame

SURVEY_DIR = f"{RESULTS}/survey"
SURVEY_POINTS = sswwf.survey_points(config)


# One test point: its recordings -> E with its interval (ssw measure).
rule survey_point:
    input:
        unpack(survey_point_inputs),
    output:
        json=f"{SURVEY_DIR}/points/{{point}}.json",
    log:
        f"{LOGS}/survey/{{point}}.log",
    benchmark:
        f"{BENCHMARKS}/survey/{{point}}.tsv"
    wildcard_constraints:
        point=sswwf.alternatives(SURVEY_POINTS),
    conda:
        SSW_ENV
    resources:
        mem_mb=lambda wc, attempt: sswwf.mem_mb("survey_point", 0) * attempt,
        runtime=lambda wc, attempt: sswwf.runtime_min("survey_point", 0) * attempt,
    params:
        inputs=lambda wc: inputs_of("survey_point", wc.point),
        digest=lambda wc: digest_of("survey_point", wc.point),
        config=STUDY_CONFIG,
        nu=lambda wc: sswwf.survey_nu(config, wc.point),
        chain=chain_flags,
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} measure {input.recordings:q} "
        "--soil-nu {params.nu:q} --config {params.config:q} {params.chain:q} --json "
        "> {output.json:q} 2> {log:q}"


# The survey table, verdicts and figures.
rule survey_table:
    input:
        expand(f"{SURVEY_DIR}/points/{{point}}.json", point=SURVEY_POINTS),
    output:
        **(
            {
                "map": report(
                    f"{SURVEY_DIR}/figures/survey_map.png",
                    caption="../report/survey_map.rst",
                    category=REPORT_CATEGORIES["survey"],
                    subcategory="Figures",
                ),
                "geojson": f"{SURVEY_DIR}/survey.geojson",
            }
            if sswwf.survey_has_coordinates(config)
            else {}
        ),
        csv=f"{SURVEY_DIR}/survey.csv",
        h5=f"{SURVEY_DIR}/survey.h5",
        plot=report(
            f"{SURVEY_DIR}/figures/survey_E.png",
            caption="../report/survey_E.rst",
            category=REPORT_CATEGORIES["survey"],
            subcategory="Figures",
        ),
    log:
        f"{LOGS}/survey/survey_table.log",
    benchmark:
        f"{BENCHMARKS}/survey/survey_table.tsv"
    conda:
        SSW_ENV
    params:
        inputs=inputs_of("survey_table"),
        digest=digest_of("survey_table"),
        config=STUDY_CONFIG,
        map=lambda wc, output: (
            ["--map", output.map, "--geojson", output.geojson]
            if "map" in output.keys()
            else []
        ),
    shell:
        "python -m ssw --inputs-sha256 {params.digest:q} survey-table {input:q} "
        "--config {params.config:q} --csv {output.csv:q} --h5 {output.h5:q} "
        "--plot {output.plot:q} {params.map:q} > {log:q} 2>&1"


SURVEY_TARGETS = list(rules.survey_table.output) if SURVEY_POINTS else []

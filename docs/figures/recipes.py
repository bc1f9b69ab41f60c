"""The documentation's figures: where each comes from (read by ``docs/_ext/ssw_figures.py``).

Each figure is drawn by the code that draws it for the study (``ssw.tof.sweep.plot_fig8``,
``ssw.validation.figures``, ``ssw.bench``, ``ssw.design.output``, ``ssw.lift``), never by a
second plotting code: the site takes the study's own PNG when ``results/`` holds it (after
``make study`` or ``ssw bench``), else runs the public command below on small inputs when
the site builds (seconds; cached in ``build/docs-figures/`` until ssw's source changes).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Recipe:
    """One figure of the site.

    Parameters
    ----------
    caption : str
        What the figure shows (the page adds where it came from).
    result : str or None
        The study's PNG, relative to the repository's ``results/`` (None: the study
        makes none).
    command : tuple of str
        The small run's ``ssw`` arguments; ``{out}`` is its output folder, ``{root}`` the
        repository.
    output : str
        The PNG the small run writes, relative to ``{out}``.
    small : str
        How the small run differs from the study's (said under the figure).
    """

    caption: str
    result: str | None
    command: tuple[str, ...]
    output: str
    small: str


CI = "{root}/config/ci.yaml"

RECIPES: dict[str, Recipe] = {
    "fig8": Recipe(
        caption="TOF against the soil's Young's modulus, one line per Poisson's ratio "
        "(thesis Fig 8).",
        result="chain/figures/fig8_tof_vs_E.png",
        command=("tof-sweep", "--soil-E-min", "10e6", "--soil-E-max", "490e6",
                 "--soil-E-step", "20e6", "--soil-nu", "0.2", "0.3", "0.4", "--law", "hertz",
                 "--stress-checks", "none", "--plot", "{out}/fig8.png"),
        output="fig8.png",
        small="the thesis device on the bare-soil Hertz wall (the study: the contact FEM's "
        "exact law under the plate), 25 moduli x 3 Poisson's ratios"),
    "validation": Recipe(
        caption="Simulated against measured TOF of the thesis's validation samples, with "
        "the inverted moduli's 95 % intervals (thesis Fig 10, Tables 2 and 3).",
        result="validation/fig10_tof_validation.png",
        command=("validate", "--config", CI, "--calibration", "none", "--outdir", "{out}"),
        output="fig10_tof_validation.png",
        small="config/ci.yaml (the small study's coarser mesh), the device uncalibrated"),
    "chain-work-precision": Recipe(
        caption="Work and precision of the chain's integrator (velocity Verlet, batched "
        "and one point at a time) against DOP853: TOF error against CPU time per point.",
        result="bench/chain_work_precision.png",
        command=("bench", "chain", "--config", CI, "--spcs", "10", "20", "40", "80",
                 "--single-spcs", "20", "--rtols", "1e-6", "--batched-rtols", "1e-6", "1e-8",
                 "--repeat", "1", "--output-dir", "{out}"),
        output="chain_work_precision.png",
        small="config/ci.yaml's sweep, four step sizes and two DOP853 tolerances, timed "
        "once on the machine that built this page (`ssw bench chain` times more)"),
    "contact-work-precision": Recipe(
        caption="The contact FEM against Hertz and against the exact sphere (Sneddon 1965): "
        "the largest force error over the curve against its degrees of freedom and its "
        "time per curve, cold and with the operators cached.",
        result="bench/contact_work_precision.png",
        command=("bench", "contact", "--config", CI, "--levels", "0.4", "0.2", "0.1",
                 "--steps", "200", "--repeat", "1", "--output-dir", "{out}"),
        output="contact_work_precision.png",
        small="three mesh levels, 200 increments a curve, timed once on the machine that "
        "built this page (`ssw bench contact`: five levels, 1000 increments)"),
    "design-pareto": Recipe(
        caption="The plate design: each candidate plate's worst-case sensitivity to the "
        "soil's modulus against the sample's yield index (the trade-off the design ranks), "
        "and the sensitivity over the soil range of the recommended and the device's plate.",
        result="design/figures/thesis_pareto.png",
        command=("design", "--config", "{root}/config/config.yaml", "--calibration", "none",
                 "--soil-range", "thesis", "--materials", "pla", "--output",
                 "{out}/design.json", "--plot", "{out}/design.png"),
        output="design.png",
        small="the PLA plates only, on the device as described (the study: PLA, Al 6061 "
        "and A36 on the calibrated device)"),
    "plastic": Recipe(
        caption="A von Mises sample loaded and unloaded under the bead: force against "
        "indentation on the plastic wall's mesh, against a converged reference and Hertz.",
        result="bench/plastic_curve.png",
        command=("bench", "contact", "--plastic", "--config", CI, "--plastic-steps", "60",
                 "--output-dir", "{out}"),
        output="plastic_curve.png",
        small="60 loading increments (the benchmark: 250)"),
    "lift": Recipe(
        caption="A lift on a subgrade read as a half-space: the error of E against the "
        "lift's thickness, one line per subgrade-to-lift stiffness ratio.",
        result=None,
        command=("lift-study", "--config", CI, "--calibration", "none",
                 "--plot", "{out}/lift.png"),
        output="lift.png",
        small="config/ci.yaml's mesh, the command's default lifts"),
}

"""The equation pipeline's stages as plain data and as text, printed the way document
000's tools print them: the model as ModelingToolkit shows a system (Equations / Unknowns with
defaults / Parameters), Pantelides' lists as ModiaBase names them (vmap, eqmap, assign),
the sorted equations as "[variable]: equation", and the simulation statistics in Modia's
``simulate!(..., logStatistics = true)`` form (key names as Modia.jl prints them), with
the document's own log beside the run it printed it for (the ModiaLang pendulum with
L = 0.5 m; studies/modia_log.py runs it as the document does).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import sympy as sp

from youbot_dynamics.integrate.integrators import IntegratorStats
from youbot_dynamics.studies.equations import EXAMPLE_MODELS, MODIA_MERGE, EquationModel
from youbot_dynamics.studies.modia_log import DOCUMENT_LOG
from youbot_dynamics.studies.pipeline import PipelineResult, pretty_expression
from youbot_dynamics.studies.state_selection import ReselectedRun, simulate_with_reselection
from youbot_dynamics.studies.structure import variable_name



def document_log(model: EquationModel) -> str:
    """Document 000's statistics log of this run, if it prints one (the ModiaLang pendulum
    with L = 0.5 m only)."""
    if model.name != "modia-pendulum" or model.parameters["L"] != MODIA_MERGE["L"]:
        return "none printed for this run"
    log = DOCUMENT_LOG
    return (f"{log['algorithm']}, tolerance {log['tolerance']:g}: {log['nAcceptedSteps']} "
            f"accepted, {log['nRejectedSteps']} rejected steps, {log['nf (integrator)']} "
            f"getDerivatives! calls from the integrator ({log['nGetDerivatives']} in all), "
            f"{log['nResults']} results every {log['interval']:g} s; the nearest run here: "
            "--integrator rk45 --outputs 501 (studies/modia_log.py)")


def residual_text(expression: sp.Expr) -> str:
    """0 = residual, derivatives written x', x''."""
    return f"0 = {pretty_expression(expression)}"


def model_report(model: EquationModel) -> dict:
    """The model as ModelingToolkit prints a system: equations, unknowns with their
    defaults, parameters with their defaults."""
    return {"name": model.name,
            "equations": [f"{n}: {residual_text(e)}"
                          for n, e in zip(model.equation_names, model.equations)],
            "unknowns": {k: v for k, v in model.variables.items()},
            "parameters": dict(model.parameters)}


def dummy_reasons(result: PipelineResult) -> list[str]:
    """Why each dummy derivative was chosen: the pivots of each level and, for a level of
    one equation, the candidates' Jacobian entries compared."""
    reasons = []
    for k, level in enumerate(result.dummies.levels, start=1):
        if len(level.equations) == 1:
            entries = sorted(zip(level.candidates, level.jacobian[0], level.jacobian_at_start[0]),
                             key=lambda e: -abs(e[2]))
            reasons.append(
                f"level {k}: {level.equations[0]}: " + " > ".join(
                    f"|d{level.equations[0]}/d{c}| = |{text}| = {abs(value):.4g}"
                    for c, text, value in entries)
                + f": {level.selected[0]} is the dummy derivative")
        else:
            reasons.append(
                f"level {k}: {', '.join(level.equations)} in {', '.join(level.candidates)}: "
                "full pivoting at the start values chose "
                + ", ".join(f"{v} (pivot {p:.4g})" for v, p in zip(level.selected, level.pivots)))
    return reasons


def modia_log(stats: IntegratorStats, times: np.ndarray, n_states: int, tol: float,
              restarts: int) -> dict:
    """A run's statistics (outputs at ``times``, s; ``restarts``: new state selections)
    under the keys of Modia's logStatistics output."""
    failures = stats.rejected_steps
    return {"cpuTime": f"{stats.wall_time:.3g} s",
            "algorithm": stats.integrator,
            "FloatType": "Float64",
            "interval": f"{float(times[1] - times[0]):.3g} s",
            "tolerance": f"{tol:g} (relative tolerance)",
            "nStates": n_states,
            "nResults": len(times),
            "nf": stats.rhs_evals,
            "nJac": "n/a" if stats.jac_evals is None else stats.jac_evals,
            "nAcceptedSteps": stats.steps,
            "nRejectedSteps": "n/a" if failures is None else failures,
            "nErrTestFails": "n/a" if failures is None else failures,
            "nTimeEvents": 0, "nStateEvents": stats.events, "nRestartEvents": restarts}


def pipeline_report(result: PipelineResult,
                    runs: Sequence[tuple[str, ReselectedRun, float]] = ()) -> dict:
    """Every stage of ``result`` as plain data; ``runs``: (label, run, tol) of the
    simulations to report (changes of state selection, final state, observed variables at
    the end, Modia-form statistics)."""
    reduced = result.pantelides
    selection = result.dummies
    report = {
        "model": model_report(result.model),
        "order_lowering": {
            "new_variables": result.new_variables,
            "equations": [f"{n}: {residual_text(e)}"
                          for n, e in zip(result.lowered_names, result.lowered)]},
        "alias_elimination": {
            "aliases": [f"{a} = {v} (from {where})" for a, v, where in result.aliases],
            "equations": [f"f{i + 1}: {residual_text(e)}"
                          for i, e in enumerate(result.equations)]},
        "matching": {
            "variables": result.incidence_variables,
            "incidence": result.incidence,
            "highest_derivative_matching": result.initial_matching,
            "unmatched_equations": result.unmatched},
        "pantelides": {
            "steps": reduced.steps, "vmap": reduced.vmap(), "eqmap": reduced.eqmap(),
            "assign": reduced.assignment_names(),
            "differentiated": reduced.differentiations,
            "differentiated_equations": {
                reduced.equation_names[i]: residual_text(reduced.equations[i])
                for i in range(len(reduced.equations)) if reduced.equation_names[i]
                not in reduced.given_names},
            "n_equations": len(reduced.equations), "n_variables": len(reduced.variables),
            "structural_index": reduced.structural_index},
        "dummy_derivatives": {
            "levels": [{**vars(level), "jacobian": [[str(e) for e in row]
                                                    for row in level.jacobian]}
                       for level in selection.levels],
            "dummies": [variable_name(reduced.variables[j]) for j in selection.dummies],
            "states": [variable_name(reduced.variables[j]) for j in selection.states],
            "why": dummy_reasons(result)},
        "blt": {
            "unknowns": result.blt_variables, "equations": reduced.equation_names,
            "incidence": result.blt_incidence,
            "blocks": result.blocks,
            "sorted": [f"[{', '.join(vs)}]: {', '.join(eqs)}"
                       for eqs, vs in zip(result.blocks, result.block_variables)]},
        "tearing": result.tearing,
        "code": {
            "states": result.ode.state_names,
            "x0": result.ode.x0.tolist(),
            "derivatives": {f"{s}'": str(e) for s, e in result.ode.derivatives.items()},
            "observed": {k: str(e) for k, e in result.ode.observed.items()}},
        "simulation": [],
    }
    report["simulation"] = [simulation_record(*run) for run in runs]
    return report


def simulation_record(label: str, run: ReselectedRun, tol: float) -> dict:
    """One simulation as plain data: parameters, state selections, the final state and the
    observed variables at the end (SI), Modia-form statistics."""
    last = run.segments[-1]
    ode, solution = last.result.ode, last.solution
    final = solution.x[-1]
    observed = ode.observe(float(solution.t[-1]), final)
    times, _ = run.values(ode.state_names[0])
    return {"label": label,
            "parameters": dict(last.result.model.parameters),
            "t_end": float(solution.t[-1]),
            "state_selections": run.switches(),
            "final_state": dict(zip(ode.state_names, map(float, final))),
            "observed_at_end": {k: float(np.real(v)) for k, v in observed.items()},
            "statistics": modia_log(run.stats, times, len(ode.state_names), tol,
                                    len(run.segments) - 1),
            "document_statistics": document_log(last.result.model)}


def report_lines(report: dict) -> list[str]:
    """The report as the text the command prints, stage by stage."""
    lines = model_lines(report["model"])
    for stage in (lowering_lines, alias_lines, matching_lines, pantelides_lines, dummy_lines,
                  blt_lines, tearing_lines, code_lines, simulation_lines):
        lines += stage(report)
    return lines


def model_lines(model: dict) -> list[str]:
    """The model as ModelingToolkit prints a system."""
    lines = [f"Model {model['name']}:", f"Equations ({len(model['equations'])}):"]
    lines += [f"  {e}" for e in model["equations"]]
    lines.append(f"Unknowns ({len(model['unknowns'])}):")
    lines += [f"  {k}(t)" + ("" if v is None else f" [defaults: {k}(t) => {v}]")
              for k, v in model["unknowns"].items()]
    lines.append(f"Parameters ({len(model['parameters'])}):")
    lines += [f"  {k} [defaults: {k} => {v}]" for k, v in model["parameters"].items()]
    return lines


def lowering_lines(report: dict) -> list[str]:
    """Stage 1: the new variables of order lowering and the first-order equations."""
    lowering = report["order_lowering"]
    return ["\n== 1. order lowering",
            "new variables: " + (", ".join(lowering["new_variables"]) or "none"),
            *(f"  {e}" for e in lowering["equations"])]


def alias_lines(report: dict) -> list[str]:
    """Stage 2: the aliases eliminated and the equations left."""
    aliases = report["alias_elimination"]
    return ["\n== 2. alias elimination",
            "eliminated: " + (", ".join(aliases["aliases"]) or "none"),
            *(f"  {e}" for e in aliases["equations"])]


def matching_lines(report: dict) -> list[str]:
    """Stage 3: the incidence matrix and the matching of the highest derivatives."""
    matching = report["matching"]
    return ["\n== 3. matching (Hopcroft-Karp over the highest derivatives)",
            "variables: " + ", ".join(f"{j + 1}:{v}" for j, v in
                                      enumerate(matching["variables"])),
            *(f"  f{i + 1:<3d} {row}" for i, row in enumerate(matching["incidence"])),
            "matching: " + ", ".join(f"{v} -> {e}" for v, e in
                                     matching["highest_derivative_matching"].items()),
            "unmatched equations: " + (", ".join(matching["unmatched_equations"]) or "none")]


def pantelides_lines(report: dict) -> list[str]:
    """Stage 4: Pantelides' steps, the differentiated equations and ModiaBase's lists."""
    pant = report["pantelides"]
    lines = ["\n== 4. Pantelides"]
    lines += [f"  {s}" for s in pant["steps"]] or ["  no equation differentiated"]
    lines += [f"  {n}: {e}" for n, e in pant["differentiated_equations"].items()]
    lines += [f"{key}: " + ", ".join(f"{a} -> {b}" for a, b in pant[key].items())
              for key in ("vmap", "eqmap", "assign")]
    lines.append(f"{pant['n_equations']} equations in {pant['n_variables']} variables; "
                 f"structural index {pant['structural_index']}")
    return lines


def dummy_lines(report: dict) -> list[str]:
    """Stage 5: each level's Jacobian and selection, why, the dummies and the states."""
    dummy = report["dummy_derivatives"]
    lines = ["\n== 5. dummy derivatives (Mattsson-Soederlind)"]
    for k, level in enumerate(dummy["levels"], start=1):
        lines.append(f"level {k}: equations {', '.join(level['equations'])}; candidates "
                     f"{', '.join(level['candidates'])}")
        lines += [f"  d{name}/d(...) = [{', '.join(map(str, row))}]"
                  for name, row in zip(level["equations"], level["jacobian"])]
        lines.append(f"  selected: {', '.join(level['selected'])}")
    lines += dummy["why"]
    lines.append("dummy derivatives: " + (", ".join(dummy["dummies"]) or "none"))
    lines.append("states: " + ", ".join(dummy["states"]) + "; every other variable is an "
                 "unknown of the index-1 system (chosen at the start values; chosen again "
                 "during the run where a pivot fades)")
    return lines


def blt_lines(report: dict) -> list[str]:
    """Stage 6: the BLT-permuted incidence of the index-1 system and the sorted equations."""
    blt = report["blt"]
    return ["\n== 6. BLT of the index-1 system (states known)",
            "unknowns: " + ", ".join(f"{j + 1}:{v}" for j, v in enumerate(blt["unknowns"])),
            *(f"  {name:<4s} {row}" for name, row in zip(blt["equations"], blt["incidence"])),
            "sorted equations ([variables]: equations, in solution order):",
            *(f"  {s}" for s in blt["sorted"])]


def tearing_lines(report: dict) -> list[str]:
    """Stage 7: each algebraic loop's tearing variables, residuals and causal equations."""
    lines = ["\n== 7. tearing"]
    if not report["tearing"]:
        lines.append("no algebraic loop")
    for torn in report["tearing"]:
        lines.append(f"tearing variables: {', '.join(torn['tearing_variables'])}; residuals: "
                     f"{', '.join(torn['residuals'])}")
        lines += [f"  {c}" for c in torn["causal"]]
    return lines


def code_lines(report: dict) -> list[str]:
    """Stage 8: the generated ODE and its observed variables."""
    code = report["code"]
    return ["\n== 8. generated ODE x' = f(t, x), x = (" + ", ".join(code["states"]) + ")",
            *(f"  {k} = {v}" for k, v in code["derivatives"].items()),
            "observed:",
            *(f"  {k} = {v}" for k, v in code["observed"].items())]


def simulation_lines(report: dict) -> list[str]:
    """Stage 9: each run's parameters, state selections, end values and statistics."""
    lines = ["\n== 9. simulation"] if report["simulation"] else []
    for run in report["simulation"]:
        lines.append(f"{run['label']}: parameters " + ", ".join(
            f"{k} = {v:g}" for k, v in run["parameters"].items()))
        lines += [f"  state selection: {switch}" for switch in run["state_selections"]]
        lines.append(f"  at t = {run['t_end']:g} s: " + ", ".join(
            f"{k} = {v:.6g}" for k, v in {**run["final_state"], **run["observed_at_end"]}.items()))
        lines.append("  statistics (Modia's log form):")
        lines += [f"        {k:<15s} = {v}" for k, v in run["statistics"].items()]
        lines.append(f"  document 000's log: {run['document_statistics']}")
    return lines


@dataclass(frozen=True)
class PipelineConfig:
    """The pipeline on one of EXAMPLE_MODELS: a parameter ``merge`` (model | {name:
    value}; empty: the defaults, and for modia-pendulum also the document's merge L = 0.5),
    the integrator, its accuracy ``tol`` (rtol = tol, atol_i = tol max(|x0_i|, 1e-3)), the
    output times, a fixed step ``dt`` (s), the step budget of a fixed-step run, and
    whether to keep the start's state selection (``static_selection``)."""

    example: str = "pendulum"
    merge: tuple[tuple[str, float], ...] = ()
    integrator: str = "cvode_bdf"
    tol: float = 1e-6
    outputs: int = 201
    dt: float | None = None
    max_steps: int | None = None
    static_selection: bool = False


def pipeline_models(config: PipelineConfig) -> list[tuple[str, EquationModel]]:
    """(label, model) of each simulation: the example with the merge, or its defaults
    (and the document's merge for modia-pendulum)."""
    model = EXAMPLE_MODELS[config.example]()
    merges = [dict(config.merge)] if config.merge else [{}]
    if config.example == "modia-pendulum" and not config.merge:
        merges.append(MODIA_MERGE)
    return [("model | " + ", ".join(f"{k} = {v:g}" for k, v in merge.items())
             if merge else "model (defaults)", model | merge) for merge in merges]


def run(config: PipelineConfig) -> dict:
    """Every stage of the pipeline and the simulations, as plain data
    (:func:`pipeline_report`); IntegrationError if a simulation fails."""
    runs = []
    for label, model in pipeline_models(config):
        with np.errstate(all="ignore"):
            run = simulate_with_reselection(
                model, config.integrator, config.tol, config.outputs, dt=config.dt,
                max_steps=config.max_steps,
                max_segments=1 if config.static_selection else 100)
        runs.append((label, run, config.tol))
    return pipeline_report(runs[0][1].segments[0].result, runs)


def text(report: dict) -> str:
    """The report as the text ``study pipeline`` prints."""
    return "\n".join(report_lines(report))

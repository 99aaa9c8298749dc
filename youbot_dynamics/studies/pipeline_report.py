"""The equation pipeline's stages as plain data and as text, printed the way the seed's
tools print them: the model as ModelingToolkit shows a system (Equations / Unknowns with
defaults / Parameters), Pantelides' lists as ModiaBase names them (vmap, eqmap, assign),
the sorted equations as "[variable]: equation", and the simulation statistics in Modia's
``simulate!(..., logStatistics = true)`` form (key names as Modia.jl prints them; the seed's
own log is not in benchmarks.md, so its column says so).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
import sympy as sp

from youbot_dynamics.integrate.integrators import IntegratorStats
from youbot_dynamics.studies.equations import EquationModel
from youbot_dynamics.studies.pipeline import PipelineResult, pretty_expression
from youbot_dynamics.studies.state_selection import ReselectedRun
from youbot_dynamics.studies.structure import variable_name

#: What benchmarks.md gives of the seed's statistics log.
SEED_LOG = "not given (benchmarks.md has no statistics log of the seed)"


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
    for label, run, tol in runs:
        last = run.segments[-1]
        ode, solution = last.result.ode, last.solution
        final = solution.x[-1]
        observed = ode.observe(float(solution.t[-1]), final)
        times, _ = run.values(ode.state_names[0])
        report["simulation"].append({
            "label": label,
            "parameters": dict(last.result.model.parameters),
            "t_end": float(solution.t[-1]),
            "state_selections": run.switches(),
            "final_state": dict(zip(ode.state_names, map(float, final))),
            "observed_at_end": {k: float(np.real(v)) for k, v in observed.items()},
            "statistics": modia_log(run.stats, times, len(ode.state_names), tol,
                                    len(run.segments) - 1),
            "seed_statistics": SEED_LOG})
    return report


def report_lines(report: dict) -> list[str]:
    """The report as the text the command prints, stage by stage."""
    model = report["model"]
    lines = [f"Model {model['name']}:", f"Equations ({len(model['equations'])}):"]
    lines += [f"  {e}" for e in model["equations"]]
    lines.append(f"Unknowns ({len(model['unknowns'])}):")
    lines += [f"  {k}(t)" + ("" if v is None else f" [defaults: {k}(t) => {v}]")
              for k, v in model["unknowns"].items()]
    lines.append(f"Parameters ({len(model['parameters'])}):")
    lines += [f"  {k} [defaults: {k} => {v}]" for k, v in model["parameters"].items()]

    lowering = report["order_lowering"]
    lines.append("\n== 1. order lowering")
    lines.append("new variables: " + (", ".join(lowering["new_variables"]) or "none"))
    lines += [f"  {e}" for e in lowering["equations"]]
    aliases = report["alias_elimination"]
    lines.append("\n== 2. alias elimination")
    lines.append("eliminated: " + (", ".join(aliases["aliases"]) or "none"))
    lines += [f"  {e}" for e in aliases["equations"]]

    matching = report["matching"]
    lines.append("\n== 3. matching (Hopcroft-Karp over the highest derivatives)")
    lines.append("variables: " + ", ".join(f"{j + 1}:{v}" for j, v in
                                            enumerate(matching["variables"])))
    lines += [f"  f{i + 1:<3d} {row}" for i, row in enumerate(matching["incidence"])]
    lines.append("matching: " + ", ".join(f"{v} -> {e}" for v, e in
                                          matching["highest_derivative_matching"].items()))
    lines.append("unmatched equations: " + (", ".join(matching["unmatched_equations"])
                                            or "none"))

    pant = report["pantelides"]
    lines.append("\n== 4. Pantelides")
    lines += [f"  {s}" for s in pant["steps"]] or ["  no equation differentiated"]
    lines += [f"  {n}: {e}" for n, e in pant["differentiated_equations"].items()]
    for key in ("vmap", "eqmap", "assign"):
        lines.append(f"{key}: " + ", ".join(f"{a} -> {b}" for a, b in pant[key].items()))
    lines.append(f"{pant['n_equations']} equations in {pant['n_variables']} variables; "
                 f"structural index {pant['structural_index']}")

    dummy = report["dummy_derivatives"]
    lines.append("\n== 5. dummy derivatives (Mattsson-Soederlind)")
    for k, level in enumerate(dummy["levels"], start=1):
        lines.append(f"level {k}: equations {', '.join(level['equations'])}; candidates "
                     f"{', '.join(level['candidates'])}")
        for name, row in zip(level["equations"], level["jacobian"]):
            lines.append(f"  d{name}/d(...) = [{', '.join(map(str, row))}]")
        lines.append(f"  selected: {', '.join(level['selected'])}")
    lines += dummy["why"]
    lines.append("dummy derivatives: " + (", ".join(dummy["dummies"]) or "none"))
    lines.append("states: " + ", ".join(dummy["states"]) + "; every other variable is an "
                 "unknown of the index-1 system (chosen at the start values; chosen again "
                 "during the run where a pivot fades)")

    blt = report["blt"]
    lines.append("\n== 6. BLT of the index-1 system (states known)")
    lines.append("unknowns: " + ", ".join(f"{j + 1}:{v}" for j, v in enumerate(blt["unknowns"])))
    lines += [f"  {name:<4s} {row}" for name, row in zip(blt["equations"], blt["incidence"])]
    lines.append("sorted equations ([variables]: equations, in solution order):")
    lines += [f"  {s}" for s in blt["sorted"]]

    lines.append("\n== 7. tearing")
    if not report["tearing"]:
        lines.append("no algebraic loop")
    for torn in report["tearing"]:
        lines.append(f"tearing variables: {', '.join(torn['tearing_variables'])}; residuals: "
                     f"{', '.join(torn['residuals'])}")
        lines += [f"  {c}" for c in torn["causal"]]

    code = report["code"]
    lines.append("\n== 8. generated ODE x' = f(t, x), x = (" + ", ".join(code["states"]) + ")")
    lines += [f"  {k} = {v}" for k, v in code["derivatives"].items()]
    lines.append("observed:")
    lines += [f"  {k} = {v}" for k, v in code["observed"].items()]

    if report["simulation"]:
        lines.append("\n== 9. simulation")
    for run in report["simulation"]:
        lines.append(f"{run['label']}: parameters " + ", ".join(
            f"{k} = {v:g}" for k, v in run["parameters"].items()))
        lines += [f"  state selection: {switch}" for switch in run["state_selections"]]
        lines.append(f"  at t = {run['t_end']:g} s: " + ", ".join(
            f"{k} = {v:.6g}" for k, v in {**run["final_state"], **run["observed_at_end"]}.items()))
        lines.append("  statistics (Modia's log form):")
        lines += [f"        {k:<15s} = {v}" for k, v in run["statistics"].items()]
        lines.append(f"  seed's log: {run['seed_statistics']}")
    return lines

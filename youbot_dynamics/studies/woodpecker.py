"""The woodpecker toy (document 001 section 3) as a hybrid
system: a sleeve (mass mS, inertia JS) slides and tilts on a vertical bar of radius r0, the
bird (mB, JB) hangs on it by a rotational spring cp.

State x = (z, phiS, phiB, z', phiS', phiB'): sleeve height (m), sleeve and bird angles
(rad) and their rates. Three modes:

- ``I`` free: M q'' = f(q);
- ``II`` sleeve blocked at hS phiS = -(rS - r0) (lower right and upper left corners);
- ``III`` blocked at hS phiS = rS - r0 (lower left and upper right corners).

In a blocked mode the constraints g = (rS - r0) +- hS phiS = 0 and z' + rS phiS' = 0
(sticking) give G = [[0, +-hS, 0], [1, rS, 0]] and the index-1 form
[M G^T; G 0] [q''; lambda] = [f; 0] (g is linear in q: no curvature term). M is constant
and f is affine in x, so each mode is x' = A x + b and lambda = L x + l: the matrices are
solved once. lambda1 (N) is the corner normal force multiplier, lambda2 (N) the sticking
friction; a compressive contact has lambda1 < 0 (the force -G^T lambda pushes the sleeve
back into its admissible range; the document's resting initial state has lambda1 < 0).

Switches, exactly the document's: blocking I -> II (phiS falls to the lower stop, phiB' < 0)
and I -> III (phiS rises to the upper stop, phiB' > 0) by a perfectly plastic impact:
z' = phiS' = 0 and the bird's generalised momentum
(M v)_3 = mB lG z' + mB lS lG phiS' + (JB + mB lG^2) phiB' is kept; II -> I when lambda1
changes sign; III -> I when lambda1 changes sign with phiB' < 0; the beak hits the bar in
III when hB phiB reaches lS + lG - lB - r0 with phiB' > 0: phiB' changes sign, the mode
stays III. A blocking impact leaves lambda1 > 0 (tensile) for the first milliseconds of
II and III (lambda is affine in phiB alone here): the document's rules keep the contact until
that sign changes (II: the sleeve is then released and re-blocks; III: held by the
phiB' < 0 condition until after the beak hit). The phiB' conditions on blocking let phiS
pass the upper stop by about 1.5e-3 rad after a III release, as in the document's model.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from youbot_dynamics.integrate.events import HybridSolution, Mode, Transition, simulate_hybrid
from youbot_dynamics.studies.stats_table import stats_table

STATE_NAMES = ("z", "phiS", "phiB", "dz", "dphiS", "dphiB")
MODES = ("I", "II", "III")
#: Switch kinds: blocking impacts, releases and the beak hit.
BLOCK_II, BLOCK_III, RELEASE_II, RELEASE_III, BEAK = (
    "block_II", "block_III", "release_II", "release_III", "beak")
#: Document 001's initial state, in mode II. lambda is no state here but an output of the
#: state: (lambda1, lambda2) = (-0.69113, -0.14163) N at it, as the start values of the
#: document's own Dymola listing (-0.6911, -0.1416), not its text's (-0.628993, 0.047088).
SEED_INITIAL_MODE = "II"
SEED_INITIAL_STATE = (0.0, -0.10344, -0.65, 0.0, 0.0, 0.0)
#: Document 001's counts over [0, 2] s (Tables 15 and 16).
SEED_BEAK_HITS = 22
SEED_FIGURES = {
    "Assimulo IDA (document)": {"steps": 7228, "rhs_evals": 9254, "jac_evals": 3132,
                            "events": 224, "wall_time": 1.75},
    "Dymola (document)": {"steps": 3239, "rhs_evals": 8332, "jac_evals": 1460,
                      "events": 177, "wall_time": 0.0343},
}


@dataclass(frozen=True)
class WoodpeckerParameters:
    """Document 001's parameters (SI: kg, kg m^2, m, N m/rad, m/s^2)."""

    mS: float = 3.0e-4
    JS: float = 5.0e-9
    mB: float = 4.5e-3
    JB: float = 7.0e-7
    r0: float = 2.5e-3
    rS: float = 3.1e-3
    hS: float = 5.8e-3
    lS: float = 1.0e-2
    lG: float = 1.5e-2
    hB: float = 2.0e-2
    lB: float = 2.01e-2
    cp: float = 5.6e-3
    g: float = 9.81


class Woodpecker:
    """The woodpecker's matrices, modes and switches for one parameter set."""

    def __init__(self, parameters: WoodpeckerParameters = WoodpeckerParameters()) -> None:
        self.p = parameters

    @cached_property
    def mass_matrix(self) -> np.ndarray:
        """M acting on (z'', phiS'', phiB'') (kg, kg m, kg m^2)."""
        p = self.p
        return np.array([[p.mS + p.mB, p.mB * p.lS, p.mB * p.lG],
                         [p.mB * p.lS, p.JS + p.mB * p.lS ** 2, p.mB * p.lS * p.lG],
                         [p.mB * p.lG, p.mB * p.lS * p.lG, p.JB + p.mB * p.lG ** 2]])

    @cached_property
    def force_affine(self) -> tuple[np.ndarray, np.ndarray]:
        """f(x) = F x + f0: gravity and the spring cp (phiB - phiS) between sleeve and bird."""
        p = self.p
        F = np.zeros((3, 6))
        F[1, 1:3] = -p.cp, p.cp
        F[2, 1:3] = p.cp, -p.cp
        f0 = np.array([-(p.mS + p.mB) * p.g, -p.mB * p.lS * p.g, -p.mB * p.lG * p.g])
        return F, f0

    def constraint_jacobian(self, mode: str) -> np.ndarray:
        """G of a blocked mode: rows d/dq of (rS - r0) +- hS phiS and of z + rS phiS."""
        sign = 1.0 if mode == "II" else -1.0
        return np.array([[0.0, sign * self.p.hS, 0.0], [1.0, self.p.rS, 0.0]])

    @cached_property
    def affine_modes(self) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Per mode (A, b, L, l): x' = A x + b and lambda = L x + l (lambda = 0 in I)."""
        M = self.mass_matrix
        F, f0 = self.force_affine
        result = {}
        for mode in MODES:
            if mode == "I":
                K, rows = M, 3
            else:
                G = self.constraint_jacobian(mode)
                K, rows = np.block([[M, G.T], [G, np.zeros((2, 2))]]), 5
            rhs_x, rhs_0 = np.zeros((rows, 6)), np.zeros(rows)
            rhs_x[:3], rhs_0[:3] = F, f0
            solved_x, solved_0 = np.linalg.solve(K, rhs_x), np.linalg.solve(K, rhs_0)
            A, b = np.zeros((6, 6)), np.zeros(6)
            A[:3, 3:] = np.eye(3)
            A[3:], b[3:] = solved_x[:3], solved_0[:3]
            L, l = (solved_x[3:], solved_0[3:]) if rows == 5 else (np.zeros((2, 6)),
                                                                   np.zeros(2))
            result[mode] = (A, b, L, l)
        return result

    def constraint_forces(self, mode: str, x: np.ndarray) -> np.ndarray:
        """(lambda1, lambda2) (N) in the given mode at state x ((6,) or (n, 6) -> (n, 2))."""
        _, _, L, l = self.affine_modes[mode]
        return np.asarray(x) @ L.T + l

    def beak_angle(self) -> float:
        """phiB (rad) at which the beak touches the bar: hB phiB = lS + lG - lB - r0."""
        p = self.p
        return (p.lS + p.lG - p.lB - p.r0) / p.hB

    def stop_angle(self) -> float:
        """|phiS| (rad) at the sleeve's stops: hS phiS = +-(rS - r0)."""
        return (self.p.rS - self.p.r0) / self.p.hS

    def block(self, mode: str):
        """The reset map of a blocking impact into ``mode``: z' = phiS' = 0, bird momentum
        (M v)_3 kept (the perfectly plastic impact with impulse along G^T)."""
        bird_row = self.mass_matrix[2]

        def reset(t: float, x: np.ndarray) -> tuple[str, np.ndarray]:
            x[5] = bird_row @ x[3:] / bird_row[2]
            x[3] = x[4] = 0.0
            return mode, x
        return reset

    @staticmethod
    def release(t: float, x: np.ndarray) -> tuple[str, np.ndarray]:
        """Contact opens: back to the free mode, state unchanged."""
        return "I", x

    @staticmethod
    def beak_hit(t: float, x: np.ndarray) -> tuple[str, np.ndarray]:
        """The beak bounces off the bar: phiB' changes sign, the mode stays III."""
        x[5] = -x[5]
        return "III", x

    def modes(self) -> list[Mode]:
        """The three modes with their guards and resets."""
        stop, beak = self.stop_angle(), self.beak_angle()
        affine = self.affine_modes

        def mode(name: str, transitions: tuple[Transition, ...]) -> Mode:
            A, b, _, _ = affine[name]
            return Mode(name, lambda t, x: A @ x + b, transitions, jac=lambda t, x: A)

        def lambda1(name: str):
            _, _, L, l = affine[name]
            row, offset = L[0], l[0]
            return lambda t, x: row @ x + offset

        def bird_falling(t: float, x: np.ndarray) -> bool:
            return x[5] < 0.0

        def bird_rising(t: float, x: np.ndarray) -> bool:
            return x[5] > 0.0

        return [
            mode("I", (Transition(BLOCK_II, lambda t, x: x[1] + stop, self.block("II"), -1,
                                  bird_falling),
                       Transition(BLOCK_III, lambda t, x: x[1] - stop, self.block("III"), 1,
                                  bird_rising))),
            mode("II", (Transition(RELEASE_II, lambda1("II"), self.release),)),
            mode("III", (Transition(RELEASE_III, lambda1("III"), self.release, 0, bird_falling),
                         Transition(BEAK, lambda t, x: x[2] - beak, self.beak_hit, 1))),
        ]

    def simulate(self, t_end: float = 2.0, integrator: str = "rk45", *, rtol: float = 1e-6,
                 atol: float = 1e-8, n_out: int = 0, x0=SEED_INITIAL_STATE,
                 mode0: str = SEED_INITIAL_MODE, **options) -> HybridSolution:
        """Run from (mode0, x0) at t = 0 to t_end (s); outputs at n_out + 1 equally spaced
        times (0: only start and end) plus both sides of every switch."""
        t_eval = np.linspace(0.0, t_end, max(n_out, 1) + 1)
        return simulate_hybrid(self.modes(), mode0, x0, t_eval, integrator, rtol=rtol,
                               atol=atol, state_names=STATE_NAMES, **options)


@dataclass(frozen=True)
class WoodpeckerConfig:
    """One run of the toy from the document's state: ``duration`` (s), the integrator, its
    tolerances, a fixed step ``dt`` (s) for fixed-step integrators, and ``n_out`` output
    samples (0: only the switches, start and end)."""

    duration: float = 2.0
    integrator: str = "dop853"
    rtol: float = 1e-6
    atol: float = 1e-8
    dt: float | None = None
    n_out: int = 0


@dataclass
class WoodpeckerRun:
    """The run's solution (modes, states, switches, statistics) and its toy."""

    config: WoodpeckerConfig
    woodpecker: Woodpecker
    solution: HybridSolution


def run(config: WoodpeckerConfig) -> WoodpeckerRun:
    """Simulate the toy."""
    woodpecker = Woodpecker()
    options = {} if config.dt is None else {"dt": config.dt}
    solution = woodpecker.simulate(config.duration, config.integrator, rtol=config.rtol,
                                   atol=config.atol, n_out=config.n_out, **options)
    return WoodpeckerRun(config, woodpecker, solution)


def as_json(result: WoodpeckerRun) -> dict:
    """Beak hits, the switches (time in s, kind, modes), the final state and mode, the
    statistics."""
    solution = result.solution
    return {
        "beak_hits": solution.count(BEAK),
        "switches": [{"time": s.time, "kind": s.kind, "from": s.mode_before,
                      "to": s.mode_after} for s in solution.switches],
        "final_state": dict(zip(solution.state_names, solution.x[-1].tolist())),
        "final_mode": solution.mode[-1],
        "stats": solution.stats.as_dict(),
    }


def seed_json() -> dict:
    """Document 001's beak hits and statistics."""
    return {"beak_hits": SEED_BEAK_HITS, **SEED_FIGURES}


def text(result: WoodpeckerRun) -> str:
    """Beak hits beside the document's, the switches, the final state and the statistics
    table beside the document's rows."""
    config, summary = result.config, as_json(result)
    lines = [f"woodpecker toy over [0, {config.duration:g}] s with {config.integrator} "
             f"(rtol {config.rtol:g}): {summary['beak_hits']} beak hits "
             f"(document 001 over 2 s: {SEED_BEAK_HITS})"]
    lines += [f"  t = {switch['time']:.6f} s  {switch['kind']:<12} "
              f"{switch['from']} -> {switch['to']}" for switch in summary["switches"]]
    lines.append(f"final mode {summary['final_mode']}, state "
                 + ", ".join(f"{k}={v:.6g}" for k, v in summary["final_state"].items()))
    lines.append(stats_table({f"{config.integrator} (ours)": summary["stats"], **SEED_FIGURES}))
    return "\n".join(lines)

"""The guards of a contact scene's hybrid run, their reset maps, and the contact events read
back from the run's switches.

Guards (per compliant pair): ``touch`` (gap falling through 0: the approach speed goes into
the pair's ``s`` and arms its compression guard), ``compression`` (armed, normal relative
velocity rising through 0: maximum compression; disarms) and ``separation`` (gap rising
through 0; disarms); per impulsive pair ``impact`` (gap falling through 0: Newton's impulse
on the plant's velocity); per free body in a chart ``recentre`` (chart rotation reaching
``RECENTRE_ANGLE``: the chart folds into the reference pose), per body in adaptive Cardan
angles ``sequence`` (|middle angle| rising through SWITCH_ANGLE: the same attitude in the
other sequence, studies/rotations.py). Every reset map is a pure
function of (t, x) returning the new x: the flags, speeds and charts are part of x, so
nothing outside the state changes. The events (:class:`~youbot_dynamics.sim.state
.ContactEvent`) are derived afterwards from the states on both sides of each switch
(:func:`contact_events`).
"""
from __future__ import annotations

from collections import Counter
from typing import Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.contact import HuntCrossley, NewtonImpact, hunt_crossley_force
from youbot_dynamics.integrate.events import Switch, Transition
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.model.rotations import SWITCH_ANGLE, switched_angles
from youbot_dynamics.sim.model import CARDAN_SEQUENCES, MIN_APPROACH_SPEED, RECENTRE_ANGLE, SimModel
from youbot_dynamics.sim.state import ContactEvent

#: Guard values below this magnitude (m, m/s) read 0: a pair resting exactly at contact
#: would otherwise flicker across 0 at round-off level between a step's end and the
#: interpolated state there, and the root finder would see no sign change.
GUARD_RESOLUTION = 1e-12
MODE = "contact"
#: The guards that change coordinates, not contact: no contact event comes of them.
ATTITUDE_GUARDS = ("recentre", "sequence")


def snapped(value: float) -> float:
    """``value``, or 0 when its magnitude is below GUARD_RESOLUTION."""
    return 0.0 if abs(value) < GUARD_RESOLUTION else value


class ContactGuards:
    """The transitions of ``model``'s contact scene, evaluated with scratch ``data``."""

    def __init__(self, model: SimModel, data: pin.Data) -> None:
        self.model, self.data = model, data
        self.s, self.armed = model.block("s"), model.block("armed")

    # ---- kinematics at a state ------------------------------------------------------------
    def _poses(self, x: np.ndarray):
        return self.model.geometry_poses(self.data, self.model.configuration(x))

    def _approach(self, k: int, x: np.ndarray):
        """Pair k's nearest point, relative Jacobian and relative velocity at state x."""
        model, data = self.model, self.data
        q = model.configuration(x)
        pin.computeJointJacobians(model.plant.model, data, q)
        pin.updateFramePlacements(model.plant.model, data)
        return model.contact.approach(data, k, model.contact.poses(data), model.velocity(x))

    def normal_speed(self, k: int, x: np.ndarray) -> float:
        """Normal relative velocity (m/s, < 0 approaching) of pair k at state x."""
        c, _, u = self._approach(k, x)
        return float(u @ c.normal)

    def depth(self, k: int, x: np.ndarray) -> float:
        """Deepest overlap (m) of pair k at state x."""
        return max(c.depth for c in self.model.contact.points(k, self._poses(x), np.inf))

    # ---- guards ------------------------------------------------------------------------------
    def _gap(self, k: int):
        def function(t: float, x: np.ndarray) -> float:
            return snapped(self.model.contact.gap(k, self._poses(x)))
        return function

    def _armed_normal_speed(self, j: int, k: int):
        def function(t: float, x: np.ndarray) -> float:
            if x[self.armed.start + j] < 0.5:
                return -1.0
            return snapped(self.normal_speed(k, x))
        return function

    def _chart_rotation(self, b: int):
        chart = self.model.block("chart")

        def function(t: float, x: np.ndarray) -> float:
            return float(np.linalg.norm(x[chart.start + 6 * b + 3:chart.start + 6 * b + 6])) - RECENTRE_ANGLE
        return function

    def _middle_angle(self, k: int):
        def function(t: float, x: np.ndarray) -> float:
            return abs(float(self.model.cardan(x, k)[1][1])) - SWITCH_ANGLE
        return function

    # ---- resets (pure: a new x) ----------------------------------------------------------
    def _touch(self, j: int, k: int):
        def reset(t: float, x: np.ndarray):
            x = x.copy()
            x[self.s.start + j] = max(-self.normal_speed(k, x), MIN_APPROACH_SPEED)
            x[self.armed.start + j] = 1.0
            return MODE, x
        return reset

    def _disarm(self, j: int):
        def reset(t: float, x: np.ndarray):
            x = x.copy()
            x[self.armed.start + j] = 0.0
            return MODE, x
        return reset

    def _impact(self, k: int):
        law: NewtonImpact = self.model.contact.pairs[k].law

        def reset(t: float, x: np.ndarray):
            model = self.model
            c, relative, u = self._approach(k, x)
            if -float(u @ c.normal) < law.rest_speed:
                raise IntegrationError(
                    f"pair {model.contact.pairs[k].name}: impact at {-float(u @ c.normal):.3g} m/s below "
                    f"rest_speed {law.rest_speed:g} m/s at t={t:.6g} s: the impulsive law carries impacts, "
                    "not resting contact (shorten the duration or use hunt_crossley or the constraint stepper)")
            inverse = model.inverse_mass(self.data, model.configuration(x))
            _, change = model.contact.impact_impulse(inverse, relative, u, c.normal, k)
            x = x.copy()
            x[model.velocity_block] += change
            return MODE, x
        return reset

    def _recentre(self):
        def reset(t: float, x: np.ndarray):
            return MODE, self.model.recentred(x)
        return reset

    def _switch_sequence(self, k: int):
        j = self.model.block("cardan").start + 4 * self.model.bodies_in["cardan_adaptive"].index(k)

        def reset(t: float, x: np.ndarray):
            sequence, angles = self.model.cardan(x, k)
            target = CARDAN_SEQUENCES[1 - CARDAN_SEQUENCES.index(sequence)]
            x = x.copy()
            x[j:j + 3] = switched_angles(target, angles)
            x[j + 3] = CARDAN_SEQUENCES.index(target)
            return MODE, x
        return reset

    def transitions(self) -> tuple[Transition, ...]:
        """Every guard of the scene with its reset map."""
        names = [p.name for p in self.model.contact.pairs]
        out = []
        for j, k in enumerate(self.model.compliant):
            out.append(Transition(f"touch:{names[k]}", self._gap(k), self._touch(j, k), -1))
            out.append(Transition(f"compression:{names[k]}", self._armed_normal_speed(j, k), self._disarm(j), +1))
            out.append(Transition(f"separation:{names[k]}", self._gap(k), self._disarm(j), +1))
        for k in self.model.impulsive:
            out.append(Transition(f"impact:{names[k]}", self._gap(k), self._impact(k), -1))
        for b, (name, coordinates) in enumerate(zip(self.model.body_names, self.model.coordinates)):
            if coordinates == "chart":
                out.append(Transition(f"recentre:{name}", self._chart_rotation(b), self._recentre(), +1))
            elif coordinates == "cardan_adaptive":
                out.append(Transition(f"sequence:{name}", self._middle_angle(b), self._switch_sequence(b), +1))
        return tuple(out)

    @staticmethod
    def attitude_events(switches: Sequence[Switch]) -> dict[str, int]:
        """How many of a run's switches were chart folds (``recentre``) and Cardan sequence
        switches (``sequence``)."""
        counts = Counter(switch.kind.partition(":")[0] for switch in switches)
        return {kind: counts[kind] for kind in ATTITUDE_GUARDS}

    # ---- the record --------------------------------------------------------------------------
    def contact_events(self, switches: Sequence[Switch]) -> tuple[list[ContactEvent], float]:
        """The contact events of a run's switches and the deepest overlap (m) at its
        maximum compressions: touch (approach speed, m/s), compression (normal force, N),
        separation (separation speed, m/s), impact (normal impulse, N s)."""
        model, events, deepest = self.model, [], 0.0
        index = {p.name: k for k, p in enumerate(model.contact.pairs)}
        for switch in switches:
            kind, _, name = switch.kind.partition(":")
            if kind in ATTITUDE_GUARDS:
                continue
            k = index[name]
            if kind == "touch":
                value = float(switch.state_after[self.s.start + model.compliant.index(k)])
            elif kind == "compression":
                depth = self.depth(k, switch.state_before)
                deepest = max(deepest, depth)
                law: HuntCrossley = model.contact.pairs[k].law
                value = hunt_crossley_force(depth, 0.0, law.stiffness, law.exponent, 0.0)
            elif kind == "separation":
                value = self.normal_speed(k, switch.state_before)
            else:
                value = self._normal_impulse(k, switch.state_before, switch.state_after)
            events.append(ContactEvent(switch.time, name, kind, value))
        return events, deepest

    def _normal_impulse(self, k: int, before: np.ndarray, after: np.ndarray) -> float:
        """Normal impulse (N s) of the impact that took pair k from ``before`` to ``after``:
        Lambda = (J M^-1 J^T)^-1 (u+ - u-) at the impact point."""
        c, relative, u_before = self._approach(k, before)
        inverse = self.model.inverse_mass(self.data, self.model.configuration(before))
        delassus = relative @ inverse @ relative.T
        impulse = np.linalg.solve(delassus, relative @ self.model.velocity(after) - u_before)
        return float(impulse @ c.normal)

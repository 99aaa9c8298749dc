"""Joint measurements for identification: /joint_states from a bag, checked, filtered,
differentiated and decimated.

Reading (:func:`read_joint_samples`): every sensor_msgs/JointState on the topic, matched to
the wanted joints BY NAME, time from the header stamp. A bag without the topic or with too
few samples, a message without efforts or velocities, without one of the joints, with a NaN
or infinite value, or with a stamp not after the previous one raises a one-line
UserInputError naming the bag, the topic and the sample (index and stamp).

Preprocessing (:func:`preprocess`): a zero-phase Butterworth low-pass (scipy.signal
``butter`` + ``filtfilt``, order 4, cut-off in Hz, :func:`low_pass`) on positions and
velocities; accelerations by central differences of the filtered velocities
(``np.gradient``). With ``states="measured"`` positions and velocities stay as recorded and
the accelerations are central differences of the recorded velocities: for bags whose q and v
are exact (a simulator's state, as the dynamics node records) the regressor is then evaluated
where the robot really was. The filter would otherwise round the velocity's kinks at each
reversal, where the Coulomb column tanh(v / v_s) (v_s = 0.01 rad/s) changes sign within a
millisecond, shifting each sign change by milliseconds (the node's bags: residuals of 0.1 to
0.3 N m at the wrist's reversals). The parallel filtering below makes the result low-pass
either way. Efforts stay as measured: the estimator filters them together with the
regressor's columns (Gautier's parallel filtering: the same filter on both sides of
tau = Y theta, so a sharp friction reversal is smeared alike in both), then drops ``edge``
samples at each end (filtfilt's start-up transients) and keeps every ``decimation``-th one.
The default decimation brings the rate down to twice the cut-off: the decimated samples do
not alias, and their filtered noise is close to white, as the least-squares covariance
assumes.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
import scipy.signal
from tqdm import tqdm

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.bag_reader import bag_topics, read_bag
from youbot_dynamics.io.stamps import stamp_ns_of

#: Fewer samples than this cannot carry an identification (and filtfilt needs 3 x 15).
MIN_SAMPLES = 50
FILTER_ORDER = 4


@dataclass(frozen=True)
class JointSamples:
    """Measured joint states: ``t`` (N,) s from the first stamp, ``q`` (rad), ``v``
    (rad/s), ``effort`` (N m), each (N, n) in ``joint_names`` order."""

    joint_names: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    effort: np.ndarray

    @property
    def rate(self) -> float:
        """Sampling rate, Hz (from the median stamp spacing)."""
        return float(1.0 / np.median(np.diff(self.t)))


@dataclass(frozen=True)
class Motion:
    """Samples ready for the regressor: filtered q, v and their derivative a (rad, rad/s,
    rad/s^2), measured effort (N m), (N, n) each, at times ``t`` (s) sampled at ``rate``
    (Hz); ``cutoff`` (Hz) of the filter used, ``kept`` the samples the estimator uses (edges
    dropped, decimated)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    effort: np.ndarray
    rate: float
    cutoff: float
    kept: slice


def read_joint_samples(path: str | Path, joints: Sequence[str], topic: str = "/joint_states",
                       progress: bool = False) -> JointSamples:
    """The wanted joints' states from the bag at ``path`` (see the module docstring)."""
    counts = {t.topic: t.message_count for t in bag_topics(path)}
    where = f"bag {path}: {topic}"
    if counts.get(topic, 0) < MIN_SAMPLES:
        raise UserInputError(f"{where}: {counts.get(topic, 0)} samples, identification needs at least "
                             f"{MIN_SAMPLES}")
    stamps, rows = [], []
    messages = (m for m in read_bag(path) if m.topic == topic)
    for k, record in enumerate(tqdm(messages, total=counts[topic], desc=f"reading {topic}", unit="msg",
                                    disable=not progress)):
        message = record.message
        stamp = stamp_ns_of(message.header.stamp)
        rows.append(_sample_row(message, joints, f"{where} sample {k} (stamp {stamp} ns)"))
        if stamps and stamp <= stamps[-1]:
            raise UserInputError(f"{where} sample {k}: stamp {stamp} ns is not after the previous "
                                 f"sample's {stamps[-1]} ns (stamps must increase)")
        stamps.append(stamp)
    block = np.array(rows)                                       # (N, 3, n)
    t = (np.array(stamps, dtype=np.int64) - stamps[0]) * 1e-9
    return JointSamples(tuple(joints), t, block[:, 0], block[:, 1], block[:, 2])


def _sample_row(message, joints: Sequence[str], where: str) -> np.ndarray:
    """(position, velocity, effort) of ``joints`` in one JointState, checked."""
    names = list(message.name)
    fields = {"position": message.position, "velocity": message.velocity, "effort": message.effort}
    for field, values in fields.items():
        if len(values) != len(names):
            raise UserInputError(f"{where}: {len(values)} {field} entries for {len(names)} joints "
                                 f"(identification needs positions, velocities and efforts)")
    missing = [j for j in joints if j not in names]
    if missing:
        raise UserInputError(f"{where}: joint(s) {', '.join(missing)} missing (has {', '.join(names)})")
    index = [names.index(j) for j in joints]
    row = np.array([np.asarray(values, float)[index] for values in fields.values()])
    if not np.all(np.isfinite(row)):
        field, joint = np.argwhere(~np.isfinite(row))[0]
        raise UserInputError(f"{where}: {list(fields)[field]} of {joints[joint]} is {row[field, joint]}")
    return row


def low_pass(x: np.ndarray, rate: float, cutoff: float) -> np.ndarray:
    """Zero-phase Butterworth low-pass of x along axis 0 (samples at ``rate`` Hz, cut-off Hz)."""
    b, a = scipy.signal.butter(FILTER_ORDER, cutoff / (rate / 2))
    return scipy.signal.filtfilt(b, a, x, axis=0)


#: What the regressor is evaluated at: low-passed q and v, or the recorded ones.
STATES = ("filtered", "measured")


def preprocess(samples: JointSamples, cutoff: float = 10.0, decimation: int | None = None,
               edge: int | None = None, states: str = "filtered") -> Motion:
    """Low-pass q and v at ``cutoff`` Hz (zero phase; ``states="measured"``: keep them as
    recorded) and differentiate v; the estimator will drop ``edge`` samples per end (default
    three cut-off periods) and decimate (default: to about twice the cut-off)."""
    if states not in STATES:
        raise UserInputError(f"states '{states}': choose from {', '.join(STATES)}")
    rate = samples.rate
    if not 0.0 < cutoff < rate / 2:
        raise UserInputError(f"cut-off {cutoff} Hz must be positive and below the Nyquist frequency "
                             f"{rate / 2:g} Hz of the {rate:g} Hz samples")
    # the 1e-9 keeps a 499.99999 Hz median rate from rounding 25 down to 24
    decimation = max(1, int(rate / (2.0 * cutoff) * (1 + 1e-9))) if decimation is None else int(decimation)
    edge = int(round(3.0 * rate / cutoff)) if edge is None else int(edge)
    count = len(samples.t)
    if count - 2 * edge < MIN_SAMPLES * decimation:
        raise UserInputError(f"{count} samples are too few to drop {edge} per end and decimate "
                             f"by {decimation} (need {MIN_SAMPLES * decimation + 2 * edge})")
    q, v = (low_pass(samples.q, rate, cutoff), low_pass(samples.v, rate, cutoff)) if states == "filtered" \
        else (samples.q, samples.v)
    return Motion(samples.t, q, v, np.gradient(v, samples.t, axis=0), samples.effort, rate, cutoff,
                  slice(edge, count - edge, decimation))

"""Parameter identification on the youBot arm (5 joints; wheels and fingers locked):
condition numbers of the excitation, the round trip's accuracy, and the time to identify.

Run: python bench/bench_identification.py [--harmonics 5] [--iterations 60] [--seeds 5].

1. Excitation: cond(Y_base) of the optimised Fourier series (10 s period) against its random
   starting series and against random Fourier series of the same period and harmonics in
   the same limits (median of 5), and the optimisation's wall time.
2. Round trip, per seed: a perturbed youBot (masses +-20 %, COMs moved 1 cm, inertias
   x U(0.7, 1.3), friction from U(0.2, 0.8)) records RECORD s of the excitation at 500 Hz with
   0.05 N m effort noise; identified base parameters against the truth (max |z| over 44),
   and the torque prediction RMS on a held-out random Fourier trajectory (8 s), identified
   beside the nominal URDF's.
3. Time: identify_bag on a 60 s bag at 500 Hz (30 000 samples), best of 3 (reading
   included), with the reading alone beside it: CPU time of the process.

BENCH_SMOKE=1: 2 harmonics, 1 iteration, 1 seed, bags of 4 s (preprocessing needs 3.1 s).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import PROCESS, sized, timed  # noqa: E402
from youbot_dynamics import default_urdf  # noqa: E402
from youbot_dynamics.identification import synthetic  # noqa: E402
from youbot_dynamics.identification.base_parameters import base_parameters  # noqa: E402
from youbot_dynamics.identification.excitation import (ExcitationLimits, condition_number,  # noqa: E402
                                                       optimise_excitation, random_fourier)
from youbot_dynamics.identification.identify import (ARM_JOINTS, identify_bag, layout_for,  # noqa: E402
                                                     prediction_rms)
from youbot_dynamics.identification.measurements import preprocess, read_joint_samples  # noqa: E402
from youbot_dynamics.model.robot import load_robot  # noqa: E402

NOISE, RATE, PERIOD = 0.05, 500.0, 10.0
#: s of the excitation bag, of the held-out bag, of the timed bag; identify_bag runs timed
RECORD, HELD_OUT, LONG, TIMES = sized((20.0, 8.0, 60.0, 3), (4.0, 4.0, 4.0, 1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--harmonics", type=int, default=sized(5, 2))
    parser.add_argument("--iterations", type=int, default=sized(60, 1))
    parser.add_argument("--seeds", type=int, default=sized(5, 2))
    args = parser.parse_args()
    nominal = load_robot(default_urdf())
    layout = layout_for(nominal)
    base = base_parameters(layout)
    limits = ExcitationLimits()
    excitation, cost = timed(lambda: optimise_excitation(layout, base, period=PERIOD, harmonics=args.harmonics,
                                                         iterations=args.iterations))
    elapsed = cost.cpu
    randoms = [condition_number(layout, base, random_fourier(layout, PERIOD, args.harmonics, limits,
                                                             np.random.default_rng(s))) for s in range(1, 6)]
    print(f"base parameters: {base.count} of {len(layout.names)} "
          f"({base.count - 3 * len(ARM_JOINTS)} inertial + {3 * len(ARM_JOINTS)} friction)")
    print(f"excitation ({args.harmonics} harmonics, {PERIOD:g} s): cond {excitation.initial_condition:.4g} "
          f"(random start) -> {excitation.condition:.4g} in {excitation.iterations} iterations, {elapsed:.1f} s CPU; "
          f"random Fourier median {np.median(randoms):.4g} (min {min(randoms):.4g})")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for seed in range(args.seeds):
            rng = np.random.default_rng(100 + seed)
            truth_robot = load_robot(synthetic.perturbed_urdf(default_urdf(), ARM_JOINTS, rng))
            truth = base.of(layout_for(truth_robot).standard_parameters())
            bag, held_out = folder / f"excite{seed}.mcap", folder / f"held{seed}.mcap"
            synthetic.record_joint_states(bag, truth_robot, excitation.trajectory, RECORD, RATE, NOISE, rng)
            synthetic.record_joint_states(held_out, truth_robot, random_fourier(layout, HELD_OUT, 4, limits, rng),
                                          HELD_OUT, RATE, NOISE, rng)
            result = identify_bag(bag, nominal)
            z = np.abs(result.wls.values - truth) / result.wls.std
            motion = preprocess(read_joint_samples(held_out, ARM_JOINTS))
            identified = prediction_rms(layout, base, result.wls.values, motion)
            urdf = prediction_rms(layout, base, result.nominal, motion)
            print(f"seed {seed}: max |z| {z.max():.2f} (>3: {int(np.sum(z > 3))} of {base.count}); "
                  f"cond(W) {result.wls.condition:.4g}; held-out RMS identified "
                  f"{identified.min():.4f}..{identified.max():.4f} N m (noise {NOISE}), nominal URDF "
                  f"{urdf.min():.3f}..{urdf.max():.3f} N m; flagged >10 %: {len(result.wls.flagged)}")
        long_bag = folder / "long.mcap"
        truth_robot = load_robot(synthetic.perturbed_urdf(default_urdf(), ARM_JOINTS, np.random.default_rng(7)))
        synthetic.record_joint_states(long_bag, truth_robot, excitation.trajectory, LONG, RATE, NOISE,
                                      np.random.default_rng(8))
        times, reads = [], []
        for _ in range(TIMES):
            reads.append(timed(lambda: read_joint_samples(long_bag, ARM_JOINTS), PROCESS)[1].cpu)
            times.append(timed(lambda: identify_bag(long_bag, nominal), PROCESS)[1].cpu)
        print(f"identify a {LONG:g} s bag at {RATE:g} Hz ({int(LONG * RATE)} samples): {min(times):.2f} s CPU, best "
              f"of {TIMES} (reading the bag alone {min(reads):.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

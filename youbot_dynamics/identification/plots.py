"""Plot of an identification: measured and predicted effort per joint, and the residuals."""
from __future__ import annotations

from pathlib import Path


from youbot_dynamics.identification.identify import Identification, predicted_effort


def plot_identification(result: Identification, path: str | Path) -> None:
    """Save a PNG (matplotlib, Agg): one row per joint, measured (unfiltered) and predicted
    (WLS estimate) effort in N m on the left, their difference on the right, against time (s)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    motion, names = result.motion, result.layout.robot.joint_names
    predicted = predicted_effort(result.layout, result.base, result.wls.values, motion)
    rows = len(names)
    figure, axes = plt.subplots(rows, 2, figsize=(11, 2.0 * rows), sharex=True, squeeze=False)
    for j, name in enumerate(names):
        axes[j, 0].plot(motion.t, motion.effort[:, j], lw=0.5, color="0.6", label="measured")
        axes[j, 0].plot(motion.t, predicted[:, j], lw=1.0, color="C0", label="predicted (WLS)")
        axes[j, 0].set_ylabel(f"{name}\nN m")
        axes[j, 1].plot(motion.t, motion.effort[:, j] - predicted[:, j], lw=0.5, color="C3")
        axes[j, 1].set_ylabel(f"residual, RMS {result.wls.residual_rms[j]:.3g}")
    axes[0, 0].legend(loc="upper right", fontsize="small")
    axes[-1, 0].set_xlabel("t (s)")
    axes[-1, 1].set_xlabel("t (s)")
    figure.suptitle(f"identification: {result.base.count} base parameters, cond {result.wls.condition:.3g}")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)

"""Regenerate the README's figures into docs/figures/ (run with .venv/bin/python after `make test`).

* ``or_ir_acceleration.png`` — the simulator's OR-IR case with the fault periods marked;
* the thesis' Figs. 2.11-2.16 and 3.3-3.6 from the shipped sim_48k models
  (``bearing_observer.obs_figures``);
* ``diagnosis/`` — the ``bearing-diagnose --plot`` figure set for the OR-IR case.
"""

import pathlib
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bearing_common.bearings import CATALOG, fault_frequency  # noqa: E402
from benchmarks.obs_figures import make_figures  # noqa: E402

DRIVE_END_6205 = CATALOG["6205"]  # TODO(issue 11): bearing as input
from bearing_common.states import FaultState  # noqa: E402
from bearing_sim.schedule import scenario  # noqa: E402
from bearing_sim.simulator import SimulationConfig, simulate  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "figures"
RPM = 1800.0


def or_ir_figure(run: dict, path: pathlib.Path) -> None:
    """Acceleration of the OR-IR case; ticks one fault period apart from each segment's first impact."""
    t, a = run["t"], run["accel"]
    fig, ax = plt.subplots(figsize=(11, 4))
    ax.plot(t, a, lw=0.4, color="0.25")
    top = np.max(np.abs(a)) * 1.05
    for state, color in ((FaultState.OUTER_RACE, "tab:blue"), (FaultState.INNER_RACE, "tab:red")):
        inside = run["truth"] == state
        if not inside.any():
            continue
        t0, t1 = t[inside][0], t[inside][-1]
        period = 1.0 / fault_frequency(DRIVE_END_6205, state, RPM)
        first = t0 + np.argmax(np.abs(a[inside][: int(period * run["sample_rate"])])) / run["sample_rate"]
        ticks = np.arange(first, t1, period)
        ax.vlines(ticks, top * 0.9, top, color=color, lw=1.2)
        ax.axvspan(t0, t1, color=color, alpha=0.06)
        ax.text(t0 + 0.003, top * 1.02, f"{state.label}: period {period * 1e3:.3f} ms "
                f"({1 / period:.2f} Hz)", color=color, fontsize=9)
    ax.set_ylim(-top, top * 1.12)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("drive-end housing y acceleration (m/s²)")
    ax.set_title("bearing-sim --scenario or-ir (1800 rpm, 48 kHz): ticks one fault period apart")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    run = simulate(SimulationConfig(rpm=RPM, sample_rate=48000.0), scenario("or-ir", 0.2))
    or_ir_figure(run, OUT / "or_ir_acceleration.png")
    with tempfile.TemporaryDirectory() as tmp:
        npz = pathlib.Path(tmp) / "or_ir.npz"
        np.savez(npz, **run)
        make_figures(OUT / "observer", "sim_48k", data=run)
        subprocess.run([str(ROOT / ".venv" / "bin" / "bearing-diagnose"), str(npz), "--plot",
                        str(OUT / "diagnosis")], check=True, stdout=subprocess.DEVNULL)
    print(f"figures in {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The thesis' identification and observer figures, made by the project's code (PNG).

* Figs. 2.11 / 2.14 (input nonlinearity f, here a gain), 2.13 / 2.16 (output nonlinearity
  g with its breakpoints) for the OR / IR models;
* Figs. 2.12 / 2.15: step response of the linear block ``q^-nk B/F``;
* Figs. 3.3-3.6: observer residual with the impulse train, for OR and IR data through
  the OR and IR observers.

Usage: ``python -m bearing_observer.obs_figures OUT_DIR [--model-set NAME] [--data FILE.npz]``;
``--data`` is a ``bearing-sim`` .npz (an OR-IR scenario shows all four combinations). Without
it, the figures 3.3-3.6 use the models' own responses to their trains.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bearing_observer.impulse_trains import impulse_train
from bearing_observer.model_sets import load_model_set
from bearing_observer.observer import FaultObserver


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_nonlinearities(model, path_in, path_out) -> list[Path]:
    """Input (f) and output (g) nonlinearities with breakpoints (Figs. 2.11/2.13, 2.14/2.16)."""
    plt = _plt()
    out = []
    for block, path, title in ((model.input_nonlinearity, path_in, "input nonlinearity f"),
                               (model.output_nonlinearity, path_out, "output nonlinearity g")):
        fig, ax = plt.subplots(figsize=(5, 4))
        span = np.ptp(block.x)
        v = np.linspace(block.x[0] - 0.1 * span, block.x[-1] + 0.1 * span, 400)
        ax.plot(v, block(v), "-", label=title)
        ax.plot(block.x, block.y, "o", label="breakpoints")
        ax.set_xlabel("input" if block is model.input_nonlinearity else "linear-block output x")
        ax.set_ylabel("f(u)" if block is model.input_nonlinearity else "g(x) (m/s²)")
        ax.set_title(f"{model.fault_type}: {title}")
        ax.grid(True)
        ax.legend()
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        out.append(Path(path))
    return out


def plot_step_response(model, path, seconds: float = 0.01) -> Path:
    """Step response of ``q^-nk B/F`` (Figs. 2.12 / 2.15)."""
    plt = _plt()
    n = int(seconds * model.sample_rate)
    x = model.simulate_linear(np.ones(n))
    t = np.arange(n) / model.sample_rate
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(t * 1e3, x)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("x (model units)")
    ax.set_title(f"{model.fault_type}: step response of the linear block "
                 f"(nb={model.nb}, nf={model.nf}, nk={model.nk})")
    ax.grid(True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_residual(y, obs: FaultObserver, path, title: str, seconds: float = 0.05) -> Path:
    """Residual y - y_hat with the observer's impulse train (Figs. 3.3-3.6)."""
    plt = _plt()
    out = obs.process(np.asarray(y, dtype=float))
    fs = obs.sample_rate
    n = min(y.size, int(seconds * fs))
    s = slice(y.size - n, y.size)  # last part: the estimates have settled
    t = np.arange(y.size)[s] / fs
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    axes[0].plot(t, y[s], lw=0.8, label="measurement y")
    axes[0].plot(t, out.estimate[s], lw=0.8, label="estimate ŷ")
    axes[0].legend(loc="upper right")
    axes[0].set_ylabel("m/s²")
    scale = max(np.max(np.abs(out.residual[s])), 1e-12)
    axes[1].plot(t, out.residual[s], lw=0.8, label="residual y - ŷ")
    axes[1].plot(t, scale * out.impulse_train[s], lw=0.8, label="impulse train (scaled)")
    axes[1].legend(loc="upper right")
    axes[1].set_xlabel("time (s)")
    axes[1].set_ylabel("m/s²")
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def make_figures(out_dir, model_set: str = "sim_48k", data=None) -> list[Path]:
    """Write all figures to ``out_dir``; ``data`` is a dict with ``accel``/``truth`` arrays
    (e.g. a loaded ``bearing-sim`` .npz) or None. Returns the paths written."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    models = load_model_set(model_set)
    paths = []
    numbers = {"outer_race": ("2_11", "2_12", "2_13"), "inner_race": ("2_14", "2_15", "2_16")}
    for ft, m in models.items():
        fi, st, fo = numbers[ft]
        paths += plot_nonlinearities(m, out_dir / f"fig{fi}_{ft}_input_nonlinearity.png",
                                     out_dir / f"fig{fo}_{ft}_output_nonlinearity.png")
        paths.append(plot_step_response(m, out_dir / f"fig{st}_{ft}_step_response.png"))
    # residual figures 3.3-3.6: data of each fault through each observer
    fig_no = iter(("3_3", "3_4", "3_5", "3_6"))
    for data_ft in ("outer_race", "inner_race"):
        if data is not None:
            truth = np.asarray(data["truth"])
            code = 1 if data_ft == "outer_race" else 2
            y = np.asarray(data["accel"], dtype=float)[truth == code]
        else:
            m = models[data_ft]
            n = int(0.3 * m.sample_rate)
            kw = {}
            if m.modulated:
                kw = dict(shaft_frequency=m.rpm / 60.0, offset=m.train_offset)
            y = m.simulate(impulse_train(n, m.sample_rate, m.fault_frequency, phase=1.0, **kw))
        if y.size == 0:
            continue
        for obs_ft in ("outer_race", "inner_race"):
            obs = FaultObserver(models[obs_ft])
            name = f"fig{next(fig_no)}_residual_{obs_ft}_observer_{data_ft}_data.png"
            paths.append(plot_residual(y, obs, out_dir / name,
                                       f"{obs_ft} observer on {data_ft} data ({model_set})"))
    return paths


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m bearing_observer.obs_figures")
    p.add_argument("out_dir")
    p.add_argument("--model-set", default="sim_48k")
    p.add_argument("--data", default=None, help="bearing-sim .npz")
    a = p.parse_args(argv)
    data = dict(np.load(a.data)) if a.data else None
    for path in make_figures(a.out_dir, a.model_set, data):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

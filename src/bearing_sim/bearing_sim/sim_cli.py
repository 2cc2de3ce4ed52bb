"""``bearing-sim``: run the 29-DOF simulator over a scenario or schedule, write an .npz.

    bearing-sim (--scenario NAME | --schedule SPEC) [--duration S] [--sample-rate HZ]
                [--rpm RPM | --rpm-profile T0:RPM0,T1:RPM1,...] [--speed-wobble FRACTION:PERIOD]
                [--noise-density X] [--variant V] [--seed N] --out FILE.npz

The .npz holds ``t`` (s), ``accel`` (drive-end housing y acceleration, m/s^2),
``unbalance`` (physical unbalance force on the disk along +y, N), ``sample_rate``
(Hz), ``rpm``, ``truth`` (per-sample FaultState integers) and ``source`` = ``simulator``
(without it a .npz is read as a real machine's recording). With a changing speed
(``--rpm-profile``, piecewise linear in seconds:rev/min from t = 0, held after its last
point; ``--speed-wobble`` multiplies it by 1 + FRACTION·sin(2π t / PERIOD)) it also holds
``shaft_speed`` (rad/s, one value per sample) and ``rpm`` is the mean speed. Bad arguments
give one error line on stderr and exit status 2; a simulation failure exit 1.
"""

import argparse
import os
import sys
import time

from .model_parameters import DEFAULT_NOISE_DENSITY, VARIANTS
from .schedule import DEFAULT_SEGMENT_DURATION, SCENARIOS, parse_schedule, scenario, speed_profile


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"bearing-sim: error: {message}\n")


def build_parser():
    p = _Parser(prog="bearing-sim", description="Simulate drive-end bearing vibration (29-DOF model).")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--scenario", help=f"one of: {', '.join(SCENARIOS)}")
    src.add_argument("--schedule", help="fault:seconds list, e.g. 'normal:0.1,outer_race:0.2,inner_race:0.2'")
    p.add_argument("--duration", type=float, default=DEFAULT_SEGMENT_DURATION,
                   help="seconds per scenario segment (default %(default)s)")
    p.add_argument("--sample-rate", type=float, default=48000.0, help="output rate, Hz (default %(default)s)")
    speed = p.add_mutually_exclusive_group()
    speed.add_argument("--rpm", type=float, default=1800.0, help="shaft speed, rev/min (default %(default)s)")
    speed.add_argument("--rpm-profile", metavar="T0:RPM0,T1:RPM1,...",
                       help="changing speed, piecewise linear (seconds:rev/min), e.g. a run-up '0:900,10:1800'; "
                            "the .npz then carries shaft_speed (rad/s per sample)")
    p.add_argument("--speed-wobble", metavar="FRACTION:PERIOD",
                   help="slow speed wobble: the speed times 1 + FRACTION*sin(2 pi t / PERIOD s), e.g. 0.02:1.5")
    p.add_argument("--noise-density", type=float, default=0.0,
                   help=f"white measurement noise, (m/s^2)/sqrt(Hz); 0 = off (default); "
                        f"{DEFAULT_NOISE_DENSITY:g} matches the real CWRU normal record")
    p.add_argument("--variant", default="default", help=f"model variant: {', '.join(VARIANTS)}")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default %(default)s)")
    p.add_argument("--out", required=True, help="output .npz file")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _check_out_path(path):
    if not path.endswith(".npz"):
        raise ValueError(f"--out {path!r} must end in .npz")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"--out {path!r}: directory {folder!r} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise ValueError(f"--out {path!r} is not writable")


def main(argv=None):
    args = build_parser().parse_args(argv)
    import numpy as np

    from .simulator import SimulationConfig, Simulator  # compiled kernels (numba): not for --help
    try:
        if args.scenario is not None:
            if args.duration is None or not args.duration > 0:
                raise ValueError(f"--duration must be positive, got {args.duration!r}")
            schedule = scenario(args.scenario, args.duration)
        else:
            schedule = parse_schedule(args.schedule)
        profile = speed_profile(args.rpm, args.rpm_profile, args.speed_wobble,
                                sum(seconds for _, seconds in schedule))
        cfg = SimulationConfig(rpm=args.rpm, sample_rate=args.sample_rate, variant=args.variant,
                               noise_density=args.noise_density, seed=args.seed, speed_profile=profile)
        _check_out_path(args.out)
        sim = Simulator(cfg, schedule)
    except ValueError as exc:
        print(f"bearing-sim: error: {exc}", file=sys.stderr)
        return 2
    # progress: a live bar on a terminal (runs >= 0.5 s); in logs one line per 10 % (runs >= 5 s)
    tty = sys.stderr.isatty()
    show = not args.quiet and ((tty and sim.duration >= 0.5) or sim.duration >= 5.0)
    last_tenth = -1
    n_chunk = max(1, int(round(0.05 * sim.sample_rate)))
    parts = []
    t_start = time.perf_counter()
    try:
        while not sim.finished:
            parts.append(sim.advance(n_chunk))
            if show:
                frac = sim.samples_done / max(sim.total_samples, 1)
                el = time.perf_counter() - t_start
                text = (f"{100 * frac:5.1f}%  {sim.samples_done / sim.sample_rate:.2f}/{sim.duration:.2f} s "
                        f"simulated in {el:.1f} s")
                if tty:
                    sys.stderr.write(f"\rbearing-sim [{'#' * int(30 * frac):<30}] {text}")
                elif int(10 * frac) > last_tenth:
                    last_tenth = int(10 * frac)
                    sys.stderr.write(f"bearing-sim: {text}\n")
                sys.stderr.flush()
    except RuntimeError as exc:
        if show and tty:
            sys.stderr.write("\n")
        print(f"bearing-sim: error: {exc}", file=sys.stderr)
        return 1
    if show and tty:
        sys.stderr.write("\n")
    accel = np.concatenate([c.accel for c in parts])
    fields = dict(t=np.arange(sim.total_samples) / sim.sample_rate,
                  accel=accel,
                  unbalance=np.concatenate([c.unbalance for c in parts]),
                  sample_rate=np.float64(sim.sample_rate),
                  rpm=np.float64(cfg.rpm),
                  truth=np.concatenate([c.truth for c in parts]),
                  source=np.str_("simulator"))
    if profile is not None:
        fields["shaft_speed"] = np.concatenate([c.shaft_speed for c in parts])
        fields["rpm"] = np.float64(profile.mean_rpm(0.0, sim.duration))
    try:
        np.savez(args.out, **fields)
    except OSError as exc:
        print(f"bearing-sim: error: cannot write {args.out!r}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

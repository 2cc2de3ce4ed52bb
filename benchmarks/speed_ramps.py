"""Test data for changing speed: simulated ramps and development recordings warped along speed profiles.

    python -m benchmarks.speed_ramps [--out out/speed_ramps] [--only sim|warped] [--ramps 10,20,40]
                                     [--states normal,outer_race,inner_race] [--seconds 10]

(``make speed-data``.) Every case is a ``.npz`` as ``bearing-diagnose`` reads it: ``accel`` (m/s²),
``sample_rate`` (Hz), ``shaft_speed`` (rad/s per sample, the exact tachometer), ``rpm`` (its
mean), ``truth`` (state per sample), ``source`` (``simulator``, ``cwru``, ``mfpt``, ``mat``) and
``profile`` (the speed profile, ``T:RPM`` points); warped records also carry ``note``.

Profiles (:func:`ramp_profiles`): a ramp of ±x % over 10 s goes linearly from (1 ∓ x/200)·N to
(1 ± x/200)·N, so that its mean is the nominal speed N (1800 rev/min for the simulator, the
record's own speed for a warped record), and a run-up goes from 900 to 1800 rev/min over 10 s
(warped: from half the record's speed to its speed).

* **Simulated** (:func:`simulated_case`): the 29-DOF model along the profile, noise-free or with
  sensor noise (4.5e-3 (m/s²)/√Hz), at 12 kHz.
* **Warped** (:func:`warped_case`): each development recording of ``shared_data.yaml`` (CWRU,
  MFPT, HIT-SM; healthy and faulty) played along the profile, :mod:`bearing_recordings.speed_warp`;
  its ``shaft_speed`` is the profile times the record's own shaft speed (:func:`own_speed`), not
  times its stated one, from which the shaft's lines depart.
  Unlike a real ramp, the resonances (and electrical lines) move with the speed too, and the
  impacts keep their constant-speed strength; results on them test the speed handling, not the
  physics of a run-up. A record shorter than the profile needs covers the middle of it (the
  part centred on the nominal speed, :func:`bearing_recordings.speed_warp.centred_span`).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
from dataclasses import dataclass

import numpy as np

from bearing_common.shaft_angle import SpeedProfile
from bearing_common.states import FaultState, parse_fault
from bearing_recordings.speed_warp import centred_span, warp

MANIFEST = pathlib.Path(__file__).resolve().parent / "shared_data.yaml"

#: The issue's ramps (± % of the nominal speed over RAMP_SECONDS) and run-up.
RAMPS, RAMP_SECONDS, RUN_UP_RPM = (10, 20, 40), 10.0, (900.0, 1800.0)
SIM_RPM, SIM_RATE, SIM_NOISE = 1800.0, 12000.0, 4.5e-3

WARP_NOTE = ("constant-speed recording warped in time along the speed profile: unlike a real ramp, the "
             "resonances and electrical lines move with the speed too")


def ramp_profiles(rpm: float, ramps=RAMPS, seconds: float = RAMP_SECONDS, run_up: bool = True) -> dict:
    """Name -> SpeedProfile: ``up20``/``down20``... (± x % of ``rpm`` over ``seconds``, mean ``rpm``)
    and ``runup`` (from half of ``rpm``, or 900 rev/min for the simulator's 1800, to ``rpm``)."""
    out = {}
    for x in ramps:
        lo, hi = rpm * (1.0 - x / 200.0), rpm * (1.0 + x / 200.0)
        out[f"up{x}"] = SpeedProfile.ramp(lo, hi, seconds)
        out[f"down{x}"] = SpeedProfile.ramp(hi, lo, seconds)
    if run_up:
        out["runup"] = SpeedProfile.ramp(rpm * RUN_UP_RPM[0] / RUN_UP_RPM[1], rpm, seconds)
    return out


@dataclass
class Case:
    """One test case: the signal with its tachometer and truth, and what it is."""

    name: str
    accel: np.ndarray  # m/s²
    sample_rate: float  # Hz
    shaft_speed: np.ndarray  # rad/s per sample
    truth: np.ndarray  # FaultState per sample
    source: str
    profile: SpeedProfile
    note: str = ""

    def save(self, folder: pathlib.Path) -> pathlib.Path:
        path = folder / f"{self.name}.npz"
        spec = ",".join(f"{t:g}:{w * 30.0 / np.pi:.6g}" for t, w in zip(self.profile.times, self.profile.omegas))
        np.savez(path, accel=self.accel, sample_rate=np.float64(self.sample_rate), shaft_speed=self.shaft_speed,
                 rpm=np.float64(np.mean(self.shaft_speed) * 30.0 / np.pi), truth=self.truth.astype(np.int8),
                 source=self.source, profile=spec, note=self.note)
        return path


def simulated_case(state: FaultState, profile_name: str, noise: float = 0.0, seconds: float = RAMP_SECONDS,
                   sample_rate: float = SIM_RATE) -> Case:
    """The simulator in ``state`` along ``ramp_profiles(1800)[profile_name]`` for ``seconds`` s."""
    from bearing_sim.simulator import SimulationConfig, simulate
    profile = ramp_profiles(SIM_RPM)[profile_name]
    d = simulate(SimulationConfig(sample_rate=sample_rate, noise_density=noise, speed_profile=profile),
                 [(state, seconds)])
    tag = "noisy" if noise else "clean"
    return Case(f"sim_{state.label}_{profile_name}_{tag}", d["accel"], d["sample_rate"], d["shaft_speed"],
                d["truth"], "simulator", profile)


def warped_case(record, profile_name: str, own: np.ndarray | None = None) -> Case:
    """A manifest recording (``accuracy.LabelledRecording``) played along ``ramp_profiles(its rpm)[profile_name]``;
    its tachometer the profile times ``own``, the record's own shaft speed per sample (:func:`own_speed`), or
    times its stated speed when None."""
    rec = record.load()
    if rec.rpm is None:
        raise ValueError(f"{record.name}: the recording states no speed")
    profile = ramp_profiles(rec.rpm)[profile_name]
    start, end = centred_span(profile, rec.rpm, rec.duration)
    w = warp(rec.accel, rec.sample_rate, rec.rpm, profile, start, end, own)
    shifted = SpeedProfile(profile.times - start, profile.omegas)  # the case's time starts at 0
    name = f"{record.dataset}_{record.name}_{profile_name}".replace(" ", "_").lower()
    return Case(name, w.accel, w.sample_rate, w.shaft_speed, np.full(w.accel.size, int(record.truth)),
                rec.source, shifted, WARP_NOTE)


#: Largest relative change per second of a constant-speed recording's own shaft speed (1/s): the
#: tracker's path may follow a slow wander, not jump between line families (:func:`own_speed`).
OWN_MAX_RATE = 0.01


def own_speed(rec) -> np.ndarray:
    """A constant-speed recording's own shaft speed per sample (rad/s), as a tachometer on its shaft would
    read it: tracked from its vibration (:func:`bearing_diagnoser.order_tracking.track_speed`) within ±5 %
    of its stated speed, changing by at most :data:`OWN_MAX_RATE` per second. A data set states one nominal
    speed; the shaft's lines sit off it (HIT-SM Normal_900 by 1.2 %, MFPT by 0.6 %) and wander about
    their mean (CWRU 097 and 105: 5th-95th percentile ±0.15 %, over a few tenths of a second), which the
    tracker's coarse track resolves and its linear refinement would smooth away (hence ``linear=False``;
    with the linear track as the tachometer, CWRU 105 in 097 along ±40 % was found only at its recorded level)."""
    from bearing_diagnoser.order_tracking import track_speed
    return track_speed(rec.accel, rec.sample_rate, 0.95 * rec.rpm, 1.05 * rec.rpm, max_rate=OWN_MAX_RATE,
                       linear=False).speed


def development_records(manifest=MANIFEST) -> list:
    """The manifest's recordings that are present (each file once, as recorded: no resampled copies)."""
    from bearing_diagnoser.accuracy import load_manifest
    return [r for r in load_manifest(manifest) if not r.resample_to and r.path.is_file()]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="speed_ramps", description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/speed_ramps", help="folder for the .npz files (default %(default)s)")
    ap.add_argument("--only", choices=("sim", "warped"), help="only simulated or only warped cases")
    ap.add_argument("--ramps", default="10,20,40,runup", help="profiles: ramp percentages and 'runup'")
    ap.add_argument("--states", default="normal,outer_race,inner_race", help="simulated states")
    ap.add_argument("--seconds", type=float, default=RAMP_SECONDS, help="simulated seconds per case")
    args = ap.parse_args(argv)
    names = []
    for item in args.ramps.split(","):
        names += ["runup"] if item == "runup" else [f"up{int(item)}", f"down{int(item)}"]
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    count = 0
    if args.only != "warped":
        for state in (parse_fault(s) for s in args.states.split(",")):
            for name in names:
                for noise in (0.0, SIM_NOISE):
                    path = simulated_case(state, name, noise, args.seconds).save(out)
                    count += 1
                    print(f"speed_ramps: {path}", file=sys.stderr)
    if args.only != "sim":
        records = development_records()
        if not records:
            print(f"speed_ramps: no development recordings found beside the repository ({MANIFEST})", file=sys.stderr)
        for record in records:
            try:
                own = own_speed(record.load())
            except ValueError as exc:
                print(f"speed_ramps: skipped {record.name}: {exc}", file=sys.stderr)
                continue
            for name in names:
                try:
                    path = warped_case(record, name, own).save(out)
                except ValueError as exc:
                    print(f"speed_ramps: skipped {record.name} {name}: {exc}", file=sys.stderr)
                    continue
                count += 1
                print(f"speed_ramps: {path}", file=sys.stderr)
    print(f"speed_ramps: wrote {count} cases to {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

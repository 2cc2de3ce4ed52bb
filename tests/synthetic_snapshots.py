"""Tiny synthetic FEMTO-format snapshot folders for the tests (acc_*.csv, written by the test itself)."""

import numpy as np

FS = 25600.0


def femto_rows(start_s: float, n: int = 2560, fs: float = FS, h=None, v=None):
    """Rows hour, minute, second, microsecond, horizontal g, vertical g of one snapshot from ``start_s`` (s of day)."""
    t = start_s + np.arange(n) / fs
    t_day = np.mod(t, 86400.0)
    hour, rest = np.divmod(t_day, 3600.0)
    minute, rest = np.divmod(rest, 60.0)
    second = np.floor(rest)
    micro = np.round((rest - second) * 1e6, 1)
    rng = np.random.default_rng(int(start_s) % 1000)
    h = rng.standard_normal(n) * 0.3 if h is None else h
    v = rng.standard_normal(n) * 0.2 if v is None else v
    return np.column_stack([hour, minute, second, micro, h, v])


def write_femto_file(path, start_s, delimiter=",", **kw):
    """One ``acc_*.csv`` at ``path`` (rows of :func:`femto_rows`, 3 decimals of g as the data set)."""
    rows = femto_rows(start_s, **kw)
    lines = [delimiter.join([f"{int(r[0])}", f"{int(r[1])}", f"{int(r[2])}", f"{r[3]:.6g}", f"{r[4]:.3f}",
                             f"{r[5]:.3f}"]) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def write_femto(folder, starts, delimiter=",", **kw):
    """A folder of snapshots starting at ``starts`` (s of the day), numbered 1, 7, 13, ... as the data set."""
    folder.mkdir(parents=True, exist_ok=True)
    for i, s in enumerate(starts):
        write_femto_file(folder / f"acc_{6 * i + 1:05d}.csv", s, delimiter, **kw)
    return folder

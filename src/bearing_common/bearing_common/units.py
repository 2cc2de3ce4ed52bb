"""Unit constants: the project works in SI (REP-103); these convert what files and catalogs use,
and bound what a sample stream may plausibly claim."""

#: Standard gravity, m/s² per g (accelerometer files often store g).
STANDARD_GRAVITY = 9.80665

#: Metres per inch (bearing catalogs quote inches).
INCH = 0.0254

#: Fastest plausible sample rate (Hz): no vibration sensor samples faster; a larger rate in a
#: chunk or a file is a broken header, refused before any buffer is sized by it.
MAX_SAMPLE_RATE = 10e6

#: Slowest plausible sample rate (Hz): bearing impacts ring the structure's resonances at
#: kilohertz, which no slower stream holds; a smaller rate is a broken header (and would
#: make one sample span hours of impacts).
MIN_SAMPLE_RATE = 100.0


def sample_rate_problem(rate: float) -> str:
    """Why ``rate`` (Hz) is not a plausible vibration sample rate; "" when it is."""
    if not MIN_SAMPLE_RATE <= rate <= MAX_SAMPLE_RATE:  # also NaN
        return f"sample rate {rate!r} Hz is not plausible (expected {MIN_SAMPLE_RATE:g} Hz to {MAX_SAMPLE_RATE:g} Hz)"
    return ""

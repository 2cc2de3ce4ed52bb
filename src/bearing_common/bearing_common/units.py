"""Unit constants: the project works in SI (REP-103); these convert what files and catalogs use,
and bound what a sample stream may plausibly claim."""

#: Standard gravity, m/s² per g (accelerometer files often store g).
STANDARD_GRAVITY = 9.80665

#: Metres per inch (bearing catalogs quote inches).
INCH = 0.0254

#: Fastest plausible sample rate (Hz): no vibration sensor samples faster; a larger rate in a
#: chunk or a file is a broken header, refused before any buffer is sized by it.
MAX_SAMPLE_RATE = 10e6

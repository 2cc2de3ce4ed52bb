"""Unit constants: the project works in SI (REP-103); these convert what files and catalogs use."""

#: Standard gravity, m/s² per g (accelerometer files often store g).
STANDARD_GRAVITY = 9.80665

#: Metres per inch (bearing catalogs quote inches).
INCH = 0.0254

"""The envelope-spectrum front end, for real machines (the package map: :mod:`bearing_diagnoser`)."""

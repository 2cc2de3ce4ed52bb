"""The folding front end, for the simulator model sets (the package map: :mod:`bearing_diagnoser`)."""

"""What a person reads of a diagnosis or a trend: the evidence in physical terms, the terminal text, the HTML pages.

The JSON lines (what programs read) are the decision's own (:mod:`bearing_diagnoser.decision.segments`,
:mod:`bearing_diagnoser.health.monitor`); this package only reads them and the windows' published
scores, and draws with matplotlib only when a page is written.
"""

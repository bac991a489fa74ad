"""Evaluation: the paper's experiments (section 5) on recorded and synthetic handovers.

- :mod:`~sandbox.eval.metrics`: e_p, e_q, e_phi, recognition, time-to-correct,
  calibration, window-selection metric, bootstrap confidence intervals.
- :mod:`~sandbox.eval.loocv`: leave-one-out cross-validation of the static and
  dynamic formulations and the oracle.
- :mod:`~sandbox.eval.heldout`: test-only evaluation by a given fitted model.
- :mod:`~sandbox.eval.crosssession`: fit on some sessions, test on another
  (``--data A --test B``), and leave-one-session-out.
- :mod:`~sandbox.eval.report`: aggregation into ``report.json`` and Markdown.
- :mod:`~sandbox.eval.plots`: the paper's figures (matplotlib; imported on demand).
- :mod:`~sandbox.eval.tune`: cross-validated choice of the core's open defaults.
"""

"""Coverage of the ST code a run executed: lines and branches (IF/ELSIF/ELSE arms, CASE branches), per
file, POU and line, from gcc's own counters (gcov) read by gcovr (docs/coverage.md).

    collect.py   the loaded coverage builds: their counters written out (.gcda) into a session folder
    arms.py      the branches of the ST (arms of IF and CASE), from the builtin parser's syntax tree
    report.py    gcovr's reading of the session folder, the branches put in terms of ST arms, and the
                 reports (terminal summary, Cobertura XML, HTML)
    The pytest option `--linmot-cov` is plctest/cov_plugin.py.
"""

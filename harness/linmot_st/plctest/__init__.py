"""Testing a user's PLC code with pytest: the linmot-st pytest plugin and what it is made of.

  rig.py        Rig / RealTimeRig: the user's PLC co-simulated against emulated E1100 drives, with the
                helpers a test needs (step until a condition, expect an FB Done, variables, faults)
  condition.py  conditions in IEC text (step_until, inject_fault when=): parsed, type-checked, compiled
  scope.py      the scope: PLC variables and drive signals per scan; its PNG, VCD and CSV
  scope_plugin.py  the scope in pytest: marker, ini options, the files named in a failure report
    project.py    the user's project as the plugin sees it (ini options), its builds, project_of(config)
  stunit_lib.py the ST assertion library (st_lib/stunit/stunit.st) and how its failures read
  stunit.py     tests written in ST: discovery, the generated runner, one pytest item per test
  plugin.py     the pytest plugin (entry point pytest11 `linmot_st`): fixtures, markers, options

docs/testing.md is the user's guide.
"""

from .rig import FbFailed, FbResult, RealTimeRig, Rig, RigTimeout

__all__ = ["Rig", "RealTimeRig", "RigTimeout", "FbFailed", "FbResult"]

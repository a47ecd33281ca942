"""The main job: commission LinMot E1100 drives from a PVL file (`linmot-st commission`).

The PLC does the work (st_lib/commission/, plc_project/); this package generates its data, builds it,
runs it against emulated drives, shows progress, verifies the drives' state and writes the report.
docs/commissioning.md describes all of it.
"""

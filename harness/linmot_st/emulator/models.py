"""The drive models the emulator knows and the one factory that builds a drive of any of them.

    from linmot_st.emulator.models import make_drive
    drive = make_drive("E1100", 1, timings=DriveTimings.fast())

How to add a drive model (docs/architecture.md, "How to add a drive model"): write its parameter profile (a
data file in emulator/data/, profile.py's format), take a service table (linmot/manufacturer.py; a subset of
E1100_SERVICES or new rows with their handlers), name its quirks (linmot/model.py), and add one DriveModel to
MODELS below. Every place that builds a drive (the plctest rig, commissioning, `linmot-st emulate --drive`,
the benches, vcan) then offers it.
"""

from __future__ import annotations

from .linmot.b1100 import B1100
from .linmot.drive import E1100Drive
from .linmot.model import E1100, DriveModel

MODELS: dict[str, DriveModel] = {m.name: m for m in (E1100, B1100)}


def model_named(name: str) -> DriveModel:
    """The model called `name` (case-insensitive); ValueError naming the known ones."""
    for key, model in MODELS.items():
        if key.lower() == name.lower():
            return model
    raise ValueError(f"no drive model {name!r} (known: {', '.join(sorted(MODELS))})")


def make_drive(model: str | DriveModel = "E1100", node_id: int = 1, **options) -> E1100Drive:
    """A drive of `model` (a name from MODELS or a DriveModel) at CANopen node `node_id`; `options` are the
    drive's (profile, timings, protocol, curve_capacity_bytes, error_log, motion: linmot/drive.py)."""
    if isinstance(model, str):
        model = model_named(model)
    return (model.drive_class or E1100Drive)(node_id, model=model, **options)

"""Readers of the shared test vectors in tests/vectors/ (the one copy of each protocol example that the ST
library's, the emulator's and the PVL tools' tests all use)."""

from __future__ import annotations

import json
from functools import cache

from repo_paths import VECTORS


@cache
def load(name: str) -> dict:
    return json.loads((VECTORS / name).read_text())


def seed_curve(curve_id: int = 23):
    """The seeds' example curve (Figure 14) as the emulator stores it: 70-byte info block, data block."""
    from linmot_st.emulator.linmot.curves import Curve

    c = next(c for c in load("curve_info.json")["curves"] if c["fields"]["curve_id"] == curve_id)
    return Curve(curve_id, bytes.fromhex(c["info_block"]), b"".join(int(w, 16).to_bytes(4, "little") for w in c["data_words"]))

"""CAN bus: frames, the deterministic simulated bus in virtual time, python-can adapters.

Note for node authors (the emulator): to serve a sans-I/O node on a python-can Bus in real time, use
``linmot_st.bus.NodeServer(node, can_bus, on_start=node.power_on).start()`` and ``.stop()``; it calls
``on_frame``/``on_timer``/``next_timer_ns`` from one background thread under ``server.lock`` with times
in ns since start(). ``E1100Drive.attach(bus)`` / ``detach()`` wrap exactly that. docs/bus.md has the rest.
"""

from .bits import bus_bits, frame_length_bits, stuff_bit_count
from .faults import Fault, flip_bit, match_id, with_data
from .frame import Frame
from .pycan import NodeServer, open_bus, parse_bus_spec
from .sim import Endpoint, SimBus, TraceEntry
from .stats import BusStats

__all__ = ["Frame", "SimBus", "Endpoint", "TraceEntry", "BusStats", "Fault", "NodeServer", "open_bus",
           "parse_bus_spec", "bus_bits", "frame_length_bits", "stuff_bit_count", "flip_bit", "match_id", "with_data"]

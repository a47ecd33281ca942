"""Bus traces in files CAN tools read, written and read with python-can's own loggers and readers.

The file format follows the extension, as python-can's `can.Logger` chooses it: `.log` (candump -l),
`.asc` (Vector ASCII), `.blf` (Vector binary logging format); other extensions python-can knows
(.csv, .trc, ...) work too but are not tested here. A frame's timestamp is its end-of-frame time in
virtual seconds (when receivers take it), so the first frame of a run starting at 0 is stamped
about 0.0002 s. Frames destroyed by an error frame appear as error frames. Who sent a frame is kept
in the in-memory trace only: these formats have no field for it.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path


def trace_messages(trace: Iterable):
    """The trace as python-can Messages (as a bus monitor sees them: every frame is received)."""
    import can

    for entry in trace:
        t = entry.end_ns / 1e9
        if entry.status == "error":
            yield can.Message(timestamp=t, is_error_frame=True, is_extended_id=False, dlc=0)
        else:
            yield entry.frame.to_message(timestamp=t)


def write_trace(trace: Iterable, path) -> Path:
    import can

    path = Path(path)
    if not path.suffix:
        raise ValueError(f"trace file {path} needs an extension naming its format: .log, .asc or .blf")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = can.Logger(str(path))
    try:
        # ASC and BLF store times relative to their first event: anchor that at virtual time 0.
        if hasattr(writer, "log_event"):
            writer.log_event("linmot-st simulated bus", 0.0)
        for msg in trace_messages(trace):
            writer.on_message_received(msg)
    finally:
        writer.stop()
    return path


def read_trace(path) -> list:
    """The messages of a trace file, read back with python-can's reader for its extension."""
    import can

    return [msg for msg in can.LogReader(str(path))]

"""Reading a mission's recording back (``mission.rrd``): for tests and tools."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def read_entity(path: Path, entity_path: str) -> list[dict[str, Any]]:
    """The rows logged to one entity of a recording, in tick order (for tests and tools).

    Each row maps column names (``tick``, ``robot`` in seconds, ``GraphNodes:labels``,
    ``status``, ...) to Python values; static rows have no ``tick``. The wall-clock
    ``log_time`` column is left out.
    """
    from rerun.chunk import RrdReader

    wanted = "/" + entity_path.strip("/")
    rows: list[dict[str, Any]] = []
    for chunk in RrdReader(str(path)).store().stream().to_chunks():
        if chunk.entity_path != wanted:
            continue
        batch = chunk.to_record_batch()
        names = [n for n in batch.schema.names if n not in ("log_time", "rerun.controls.RowId")]
        columns = {name: _python_values(batch.column(name)) for name in names}
        rows.extend(
            {name: values[i] for name, values in columns.items()} for i in range(batch.num_rows)
        )
    rows.sort(key=lambda row: (row.get("tick") is not None, row.get("tick") or 0))
    return rows


def _python_values(column: Any) -> list[Any]:
    """A column's values; durations (the ``robot`` timeline) as float seconds, since
    nanoseconds do not fit Python's timedelta."""
    import pyarrow as pa

    if pa.types.is_duration(column.type):
        nanoseconds = column.cast(pa.duration("ns")).cast(pa.int64()).to_pylist()
        return [None if value is None else value / 1e9 for value in nanoseconds]
    return column.to_pylist()

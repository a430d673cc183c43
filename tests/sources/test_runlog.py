"""A run log's CSV read in blocks: the same numbers, to the bit, as the rows written, and
a bad cell named by its line wherever it sits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.sources.runlog.reader import LogMetadata, read_runlog
from umbmark.sources.runlog.writer import write_metadata

#: Rows: more than two blocks of the reader's 4096.
ROWS = 10_000


def _folder(tmp_path: Path, lines: list[str]) -> Path:
    write_metadata(tmp_path, LogMetadata(wheel_diameter=0.15, wheelbase=0.34, wheel_data="angles"))
    (tmp_path / "run.csv").write_text("time,x,y,theta,left,right\n" + "\n".join(lines) + "\n")
    return tmp_path


def test_every_row_reads_as_written_whatever_block_it_is_in(tmp_path: Path) -> None:
    rng = np.random.default_rng(4)
    values = np.column_stack([np.arange(ROWS) * 0.01, rng.normal(size=(ROWS, 5)) * 10.0])
    cells = [[repr(float(v)) for v in row] for row in values]
    lines = [",".join(row) for row in cells]
    # In the second block: a row without ground truth, a quoted cell, a row without
    # wheels, and spaces around the numbers.
    lines[5000] = ",".join([cells[5000][0], "", "", "", *cells[5000][4:]])
    lines[5001] = ",".join([cells[5001][0], f'"{cells[5001][1]}"', *cells[5001][2:]])
    lines[5002] = ",".join([*cells[5002][:4], "", ""])
    lines[9999] = " , ".join(cells[9999])
    (recording,), _ = read_runlog(_folder(tmp_path, lines))
    wheels = np.delete(np.arange(ROWS), 5002)
    truth = np.delete(np.arange(ROWS), 5000)
    assert np.array_equal(recording.wheels.time, values[wheels, 0])
    assert np.array_equal(recording.wheels.angles, values[wheels, 4:6])
    assert recording.truth is not None
    assert np.array_equal(recording.truth.time, values[truth, 0])
    assert np.array_equal(recording.truth.poses, values[truth, 1:4])


@pytest.mark.parametrize("row", [3, 6000])  # in the first block, in the second
@pytest.mark.parametrize(
    ("cell", "said"), [("abc", "y 'abc' is not a number"), ("inf", "y is inf")]
)
def test_a_bad_cell_is_named_by_its_line_in_any_block(
    tmp_path: Path, row: int, cell: str, said: str
) -> None:
    lines = [f"{0.01 * k!r},{k}.5,0.25,0.0,{2 * k},{3 * k}" for k in range(ROWS)]
    lines[row] = lines[row].replace(",0.25,", f",{cell},")
    folder = _folder(tmp_path, lines)
    with pytest.raises(umbmark.InputError) as caught:
        read_runlog(folder)
    # line 1 is the header: data row k is line k + 2
    assert str(caught.value) == f"{folder / 'run.csv'}, row {row + 2}: {said}"

"""Tidy CSV tables: written atomically, floats in shortest round-trip form, so equal numbers give equal bytes."""
import csv
import io

from dgmm.files import atomic_path


def _cell(value):
    return repr(float(value)) if isinstance(value, float) else str(value)


def write_csv(path, rows, columns=None):
    """Write ``rows`` (dicts) to ``path`` through a temporary file and a rename.

    Parameters
    ----------
    path : path-like
    rows : list of dict
    columns : sequence of str, optional
        Column order; the first row's keys by default.
    """
    columns = list(columns or (rows[0].keys() if rows else []))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows([_cell(row[name]) for name in columns] for row in rows)
    with atomic_path(path) as partial:
        partial.write_text(buffer.getvalue())


def read_csv(path):
    """Rows of a CSV file as dicts of strings."""
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def concat_csv(paths, path):
    """Concatenate CSV files with the same header into ``path``, in the order given."""
    rows = [row for source in paths for row in read_csv(source)]
    write_csv(path, rows)

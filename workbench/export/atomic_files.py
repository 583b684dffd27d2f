"""The all-at-once writers of :mod:`workbench.atomic_files`, under their old path."""

from workbench.atomic_files import (
    atomic_file,
    atomic_files,
    atomic_folder,
    check_output,
    check_outputs,
    write_text_atomic,
)

__all__ = [
    "atomic_file",
    "atomic_files",
    "atomic_folder",
    "check_output",
    "check_outputs",
    "write_text_atomic",
]

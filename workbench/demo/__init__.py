"""The papers' examples end to end (``workbench demo``)."""

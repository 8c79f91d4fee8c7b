"""Many frames per call: inputs expanded, frames run in this process, on worker
processes or on a Ray cluster, lines printed in input order (see run.py)."""

"""The fleet's tests share a Dask cluster started as processes (tests/dask_cluster.py)."""

from dask_cluster import cluster

__all__ = ["cluster"]

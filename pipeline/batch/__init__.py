"""Batches that outgrow one machine: a grid of points as arrays, integrated chunk by chunk by the compiled
batch kernels, streamed to one dataset on disk, resumable, on Dask when asked.

plan (grid → arrays, validated), runner (chunks → kernels), store (the streamed dataset), executors
(where chunks run: this process, a local Dask cluster, an existing scheduler).
"""

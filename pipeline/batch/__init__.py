"""Batches that outgrow one machine: a grid of points as arrays, integrated chunk by chunk by the compiled batch
kernels, streamed to one resumable dataset, on Dask when asked (docs/batch.md).
"""

"""Where the chunks of a sweep or census run: this machine's cores (local), a Dask cluster, or a
CUDA GPU.
"""

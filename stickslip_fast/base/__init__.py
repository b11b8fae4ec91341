"""Plumbing every layer uses: Numba options and borrowed records, status codes, Ctrl-C and
the stale-cache guard.
"""

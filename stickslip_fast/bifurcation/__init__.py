"""Periodic orbits and equilibria by Newton's method, their multipliers, and their continuation
with bifurcation detection and branch switching.
"""

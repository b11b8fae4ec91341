"""The physical model: parameters and presets, packed parameter slots, the friction law, f(y), its
Jacobian and the bordered linear algebra.
"""

"""The compiled integration core: tableaus, problem records, steppers, the one adaptive driver,
the Poincare section, trajectory and tangent kernels, and the validated settings.
"""

"""Integer ids of the constitutive laws, shared by the numba dispatch and the element classes.

One id per law kernel; :func:`elements.kernels.law_step` switches on it.  Adding a law means
adding an id here, its ``*_step`` / ``*_init`` kernels in its own module, and one branch in
each of ``_law_step`` and ``_law_init`` (elements.kernels).
"""
JENKINS = 0
CUBIC = 1
FRICTION3D = 2
COULOMB_STATIC_KINETIC = 3
COULOMB_REGULARISED = 4

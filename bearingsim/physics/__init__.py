"""The physics core: the quasi-static bearing model and what is judged from a state (docs/model.md
sections 2-6, 10, 11).  Pure JAX in float64; imports nothing but the package's infrastructure
(``errors``, ``names``, ``xla``, ``fastmath``).  The modules, in the order of the flow:

``geometry``   the bearing and its materials (``Bearing``, ``Material``)
``hertz``      Hertz point contact: elliptic integrals, K(alpha), semi-axes
``kinematics`` the operating condition, raceway control, ball kinematics, defect frequencies
``defect``     localized defects: raceway spalls and ball pits, their depth under each ball
``balls``      the per-ball Jones kernel
``newton``     the damped Newton machinery ``jones`` and ``shaft`` share
``jones``      one bearing: ring equilibrium, validity, stiffness, batch solves
``shaft``      a rigid shaft on N bearings (sets, preload)
``sweep``      cage-angle sweeps
``life``       ISO/TS 16281 rating life;  ``limits``: per-contact limits of a state
``pit``        the load an EDM pit takes away under a contact

The names a user types are offered at the package's top level (``bearingsim.solve``, ...)."""

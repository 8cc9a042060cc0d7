"""Description formats beside pkdyn's URDF: writers and importers.

Modules: :mod:`~pkdyn.model.formats.urdf_writer` (the URDF + pkdyn-extension writer the library
builders use), :mod:`~pkdyn.model.formats.gepetto` (Gepetto example-parallel-robots YAML
sidecars), :mod:`~pkdyn.model.formats.mjcf` (MJCF export and the MuJoCo bridge used for
cross-checks).

Layering: part of :mod:`pkdyn.model`; imports only :mod:`pkdyn.exceptions`,
:mod:`pkdyn.model` and :mod:`solvers`.
"""

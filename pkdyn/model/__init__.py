"""The model layer: description format, building, the robot, assembly, loading, other formats.

Modules: :mod:`~pkdyn.model.description` (parsing pkdyn's URDF extension elements),
:mod:`~pkdyn.model.build` (Pinocchio model, geometry and constraint models from a description),
:mod:`~pkdyn.model.robot` (:class:`Robot`), :mod:`~pkdyn.model.pose` (pose vectors),
:mod:`~pkdyn.model.inertia` (physically valid inertias, their repair),
:mod:`~pkdyn.model.assembly` (closure residuals, direct and inverse geometric models,
projection), :mod:`~pkdyn.model.home` (the home search and the assembly tolerance),
:mod:`~pkdyn.model.families` (the registry the robot library fills),
:mod:`~pkdyn.model.candidate` (a family's robots built once, each candidate written in place),
:mod:`~pkdyn.model.reuse` (Pinocchio datas and solvers a robot's computations keep),
:mod:`~pkdyn.model.loader` (``load``: URDF, MJCF, SDFormat) and :mod:`~pkdyn.model.formats`
(URDF writer, MJCF export and import, SDFormat, Gepetto YAML, Drake elements, onshape-to-robot
frames).

Layering: imports only :mod:`pkdyn.exceptions`, :mod:`pkdyn.progress` and :mod:`solvers`.
Library families are found through :mod:`pkdyn.model.families`, which :mod:`pkdyn.library`
fills when :mod:`pkdyn` is imported: the model layer never imports the library.
"""

"""Description formats beside pkdyn's URDF: writers and importers.

Modules: :mod:`~pkdyn.model.formats.urdf_writer` (the URDF + pkdyn-extension writer the library
builders use), :mod:`~pkdyn.model.formats.gepetto` (Gepetto example-parallel-robots YAML
sidecars), :mod:`~pkdyn.model.formats.mjcf` (MJCF export, and compiled by MuJoCo),
:mod:`~pkdyn.model.formats.mjcf_state` (joints and states mapped between Pinocchio and MuJoCo),
:mod:`~pkdyn.model.formats.mjcf_mujoco` (MuJoCo's actuator efforts, for cross-checks),
:mod:`~pkdyn.model.formats.mjcf_import` and
:mod:`~pkdyn.model.formats.mjcf_spec` (MJCF import: structure, and attributes with their
default classes), :mod:`~pkdyn.model.formats.sdf` (SDFormat import),
:mod:`~pkdyn.model.formats.graph` (the mechanism graph both importers fill, its spanning tree
and Pinocchio model), :mod:`~pkdyn.model.formats.drake` (Drake's constraint elements),
:mod:`~pkdyn.model.formats.onshape` (onshape-to-robot closing frames),
:mod:`~pkdyn.model.formats.gazebo` (``<gazebo><joint>`` loop closures in URDF),
:mod:`~pkdyn.model.formats.urdfplus` (URDF+: ``<loop>``, ``<coupling>``, ``independent``) and
:mod:`~pkdyn.model.formats.urdfplus_export` (a URDF+ file in pkdyn's elements),
:mod:`~pkdyn.model.formats.unread` (elements no importer reads: named, loop-like ones refused,
``ignore_elements``), :mod:`~pkdyn.model.formats.mjcf_inertia` (inertias as MuJoCo accepts
them),
:mod:`~pkdyn.model.formats.xacro_files` (xacro expansion),
:mod:`~pkdyn.model.formats.xmldoc` (bounded regular-file reads, XML with line numbers and no
entities).

Layering: part of :mod:`pkdyn.model`; imports only :mod:`pkdyn.exceptions`,
:mod:`pkdyn.model` and :mod:`solvers`.
"""

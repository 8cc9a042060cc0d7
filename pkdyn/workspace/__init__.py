"""Workspaces: translation, orientation (Merlet), dextrous, and Clavel's Delta figures.

Modules: :mod:`~pkdyn.workspace.limits` (limit kinds, the pose-evaluator protocol, passive-joint
margins), the evaluators :mod:`~pkdyn.workspace.legs` (leg robots: Gough-Stewart, closed form),
:mod:`~pkdyn.workspace.delta` (the Delta, closed form) and :mod:`~pkdyn.workspace.numeric`
(any robot: inverse model + coal), then :mod:`~pkdyn.workspace.translation`,
:mod:`~pkdyn.workspace.orientation`, :mod:`~pkdyn.workspace.dextrous` and
:mod:`~pkdyn.workspace.clavel`.

Layering: may import :mod:`pkdyn.model`, :mod:`pkdyn.closed_form`, :mod:`pkdyn.library`,
:mod:`pkdyn.analysis` and :mod:`solvers`; never dynamics, tripod, design, viewer, plotting or
the CLI.
"""

from pkdyn.workspace.clavel import ClavelFigures, clavel_closed_form, clavel_numeric
from pkdyn.workspace.dextrous import dextrous_workspace
from pkdyn.workspace.orientation import OrientationWorkspace, mel_study, orientation_workspace
from pkdyn.workspace.translation import TranslationWorkspace, translation_workspace

__all__ = [
    "ClavelFigures",
    "OrientationWorkspace",
    "TranslationWorkspace",
    "clavel_closed_form",
    "clavel_numeric",
    "dextrous_workspace",
    "mel_study",
    "orientation_workspace",
    "translation_workspace",
]

"""Closed-form geometric models of the library families, vectorised over poses (numpy).

One module per family: :mod:`~pkdyn.closed_form.delta` (Clavel's inverse and three-sphere direct
models), :mod:`~pkdyn.closed_form.gough_stewart` (leg lengths),
:mod:`~pkdyn.closed_form.planar_3rrr` (Pasqui's inverse model),
:mod:`~pkdyn.closed_form.five_bar` (inverse and direct models) and
:mod:`~pkdyn.closed_form.tripod` (the virtual U-P-S chains of seed 003, B_iIKMX). Each takes the
family's parameter dataclass (duck-typed) and is tested against the general numeric path.

Layering: imports only numpy, Pinocchio, :mod:`pkdyn.exceptions` and :mod:`pkdyn.model.pose`.
"""

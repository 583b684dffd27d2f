"""Inverse kinematics: closed form for PUMA-type arms, numerical for any arm.

Public entry points (see INTERFACE.md): ``analytic``, ``analytic_batch``,
``numeric``, plus the damped-least-squares tools.
"""

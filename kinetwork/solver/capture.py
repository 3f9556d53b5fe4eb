"""Capturing what the solvers print: SUNDIALS' failure chatter and CasADi's warnings go to a
file instead of the user's terminal, and reach the user in the error's words. The machinery
is the bottom layer's (``kinetwork.util``), so that the equations' own Newton solves (initial
equations, loop closures) are as quiet as the integrators."""

from ..util import SOLVER_LOCK, last_words, solver_output  # noqa: F401

"""The crank press (paper 001): its motion by the paper's RK4, by located events, as a periodic
steady state and by scipy's solve_ivp (`force_fit` fits the force law to load-travel data)."""
from mechopt.solvers.press.dynamics import events, ivp, rk4, steady_state

__all__ = ["rk4", "events", "steady_state", "ivp"]

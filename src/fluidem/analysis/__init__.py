"""Analyses: observers and functions that read the state and never change it."""

"""Builds the golden corpus under ``vectors/imc/cases`` from the definitions, deterministically."""

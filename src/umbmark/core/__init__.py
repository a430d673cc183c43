"""Foundations every layer may use: conventions (frame, signs, units), the error users
see, bounds of physical values, messages for people, statistics.

Imports nothing else of umbmark.
"""

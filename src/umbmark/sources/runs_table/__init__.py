"""The runs table: one row per run, typed in by hand or written by ``umbmark simulate``;
its reader and its writer.
"""

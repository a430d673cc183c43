"""Reading and writing files: runs tables, parameter files, results. No maths here."""

"""The UMBmark benchmark (Sec. 3): return errors, centres of gravity, E_max,syst and the
paper's 3 x SEM rule.
"""

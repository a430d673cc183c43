"""The UMBmark benchmark (Sec. 3), the return errors clustered by direction: centres of
gravity, E_max,syst and the paper's 3 x SEM rule (:mod:`umbmark.returns.clusters`).
"""

"""What is in a bag, for ``umbmark info``: a bounded scan of the topics, the transforms
and their chains, the candidates for each input, and the summary (``summary.bag_info``).
"""

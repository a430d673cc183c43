"""What is in a bag, for ``umbmark info``: a bounded look into its topics
(:mod:`~umbmark.sources.bag.info.scan`), its transforms and their chains
(:mod:`~umbmark.sources.bag.info.frames`), the candidates for each input, ranked
(:mod:`~umbmark.sources.bag.info.candidates`), and the report
(:mod:`~umbmark.sources.bag.info.report`: ``bag_info``, ``BagInfo``).
"""

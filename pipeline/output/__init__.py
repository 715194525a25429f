"""What a run leaves behind: the self-describing dataset (``dataset``), its
provenance (``provenance``) and the figures drawn from it (``figures``).
"""

"""The wire against the block: the one model of the wire in the stock (``in_stock``:
chord, depth, cutting speed) and what a trajectory cuts (``cut``: block, wire, feed
windows, the feed checks' figures)."""

"""Variation studies: many samples of one problem, solved in a pool or on a cluster and stored as they finish."""

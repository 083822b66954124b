"""Figures: each module draws the results of one analysis; no analysis imports them."""

"""Straight-line programs, CSE, operation counts, rendering through templates/, compiling."""

"""Straight-line programs, CSE, operation counts, rendering through the targets (templates in aggsym/templates/), compiling."""

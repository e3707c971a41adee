"""Straight-line programs, CSE, operation counts, rendering through the targets (templates in templates/), compiling."""

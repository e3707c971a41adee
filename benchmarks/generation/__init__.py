"""Generating code, measured: the time and peak memory of ``aggsym generate`` with KanesMethod beside it (section
1, :mod:`.measured`, :mod:`.kane`), the operation counts of the emitted C against the book's and Featherstone's
(section 2, :mod:`.opcounts`), how generation scales with the number of bodies (:mod:`.scaling`), the compile time
of a large robot's C in one file and with ``--split`` (:mod:`.compile_split`) and the parse of a 2000-link model
(section 4, :mod:`.inputs`).
"""

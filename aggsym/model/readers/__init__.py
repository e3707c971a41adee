"""The readers wing of :mod:`aggsym.model`: a file to a :class:`~aggsym.model.types.Model`.

One module per format and its source (YAML: ``yaml_reader``, ``yaml_source``, ``expressions``; URDF:
``urdf_reader``, ``xml_source``; xacro: ``xacro_reader``; MJCF: ``mjcf_reader``, ``mjcf_source``,
``mjcf_equalities``), what the tree readers share (``builder``, ``link_numbers``, ``sympy_numbers``,
``validate``), the side files (``side_files``) and the registry that chooses a reader for a file (``registry``).
A reader may use the model's types and the transforms wing (:mod:`aggsym.model.transforms`); nothing below
imports a reader.
"""

"""The Jinja templates of the code targets, one folder per target (c/, numpy/, latex/, jax/, torch/, ext/, casadi/),
installed as the package aggsym.templates (pyproject.toml): layout only; user text reaches them only through the
escaping filters (:mod:`aggsym.codegen.escape`)."""

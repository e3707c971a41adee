"""The Jinja templates of the code targets, a folder per target (c/, numpy/, latex/): layout only, user text
reaches them only through the escaping filters (:mod:`aggsym.codegen.escape`)."""

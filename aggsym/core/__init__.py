"""The program core: straight-line programs (:mod:`.program`) and the backends the recursions run on
(:mod:`.backend`).  Knows nothing of the model's mechanics or of printing."""

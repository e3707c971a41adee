"""The LaTeX target: NAME.tex, a standalone document of the equations of motion (closed forms for small models,
the intermediate form otherwise: :mod:`aggsym.codegen.latex`, its own tree printer).  Nothing to run."""
from __future__ import annotations

from ..latex import PRINTED_ROLES, latex_document
from .base import Target, file_pattern


class LatexTarget(Target):
    name = "latex"
    default = True
    stage = "latex"
    folder = "latex"
    templates = ("model.tex.j2",)
    lines = frozenset(PRINTED_ROLES)  # the straight lines of A, b, g and the factors (latex.intermediate_form)

    def file_names(self, job):
        return [f"{job.model.name}.tex"]

    def owns(self, name, file):
        return bool(file_pattern(name, ("tex",)).fullmatch(file))

    def render(self, job):
        return {f"{job.model.name}.tex": latex_document(job.model, self.template("model.tex.j2"), job.prog, job.outputs,
                                                        job.lines, job.omitted)}

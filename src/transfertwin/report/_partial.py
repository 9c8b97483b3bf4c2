"""How far a study got, and what a partial one means for its report.

A study can be analysed before it has finished (``study run`` interrupted or stopped by
``--max-experiments``). Its report is then valid for the states run so far only: Alg. 1–4
choose the best and worst state among them (a state not yet run cannot be chosen), and a
state with fewer runs so far has a wider Clopper–Pearson interval. `StudyProgress` holds
the counts (the CLI reads them from the study's stored plan); `partial_banner_html` and
`partial_line` say so in the report and on the command line, and say nothing for a
finished study. An adaptive study's planned count is an upper bound that it need not
reach, so it is never called partial here.
"""

from __future__ import annotations

from dataclasses import dataclass

from transfertwin._errors import InputError

__all__ = ["StudyProgress", "partial_banner_html", "partial_line"]


@dataclass(frozen=True)
class StudyProgress:
    """Done and planned experiments and states of a study.

    Attributes:
        done: Result rows stored (any status).
        planned: Experiments of the plan (objects × states × runs).
        states_done: Distinct (object, face, conveyor, θ) among the stored rows.
        states_planned: Objects × states of the plan.
        adaptive: Adaptive sampling: ``planned`` is then the most the study may run.

    Raises:
        InputError: On a negative count or more done than planned.
    """

    done: int
    planned: int
    states_done: int
    states_planned: int
    adaptive: bool = False

    def __post_init__(self) -> None:
        counts = (self.done, self.planned, self.states_done, self.states_planned)
        if min(counts) < 0:
            raise InputError(f"study progress: counts must be >= 0, got {counts}")
        if self.done > self.planned:
            raise InputError(
                f"study db holds {self.done} results but its plan has {self.planned} experiments"
            )
        if self.states_done > self.states_planned:
            raise InputError(
                f"study db holds {self.states_done} states but its plan has {self.states_planned}"
            )

    @property
    def partial(self) -> bool:
        """Fewer experiments done than planned (never for an adaptive study)."""
        return not self.adaptive and self.done < self.planned

    @property
    def fraction(self) -> float:
        """done / planned (1 for an empty plan)."""
        return self.done / self.planned if self.planned else 1.0


def partial_line(progress: StudyProgress) -> str:
    """One line for the command line; empty unless the study is partial."""
    if not progress.partial:
        return ""
    p = progress
    return (
        f"partial study: {p.done} of {p.planned} planned experiments done "
        f"({p.fraction:.0%}), {p.states_done} of {p.states_planned} planned states run; "
        "best/worst states are chosen among the states run so far (rerun 'study run' "
        "on the same db to finish)"
    )


def partial_banner_html(progress: StudyProgress) -> str:
    """A banner for the top of the report; empty unless the study is partial."""
    if not progress.partial:
        return ""
    p = progress
    return (
        "<p class='banner warn'><b>Partial study</b>: "
        f"{p.done} of {p.planned} planned experiments done ({p.fraction:.0%}), "
        f"{p.states_done} of {p.states_planned} planned states run. "
        "The best and worst states below are chosen among the states run so far: a "
        "state not yet run cannot be chosen, and states with fewer runs so far have "
        "wider 95 % intervals, so the advice may change as the study goes on. Run "
        "<code>transfertwin study run</code> again on the same db to finish it, then "
        "analyse again.</p>"
    )

"""blockid.workflows.stages: the search's stages, each a class in STAGES, and what a
stage may afford."""

from __future__ import annotations

from blockid.workflows.identify import EFFORTS, identify

from reference import SMALL, dead_zone_record


def test_the_nonlinearity_stage_keeps_a_state_space_degree_within_the_effort():
    """The folds lie inside the estimation range, so they cannot show how a higher
    monomial degree extrapolates beyond it: growth stops at the effort's largest planned
    degree (and within its parameter budget)."""
    from blockid.workflows.search_space import Candidate
    from blockid.workflows.stages import _affordable

    standard = EFFORTS["standard"]  # plans degrees 2 and 3, 300 parameters
    pnlss = Candidate("polynomial-state-space", {"nx": 2, "degree": 3, "monomials": "full"})
    assert _affordable(pnlss, (1, 1), standard)
    assert not _affordable(pnlss.with_options(degree=4), (1, 1), standard)
    assert _affordable(pnlss.with_options(degree=4), (1, 1), EFFORTS["thorough"])
    assert not _affordable(pnlss.with_options(nx=8), (1, 1), standard)  # 494 > 300
    assert _affordable(Candidate("hammerstein", {"na": 2, "nb": 2, "nk": 1}), (1, 1), standard)


def test_a_stage_is_one_class_in_the_list_of_stages():
    """A new stage is a class with a name and a run(search, context), given to identify
    in its list of stages (``stages=``, no patched module): it sees what the stages
    before it left (the delays, the ARX orders) and its candidates are scored, ranked
    and recorded like every other."""
    from blockid.workflows import stages
    from blockid.workflows.search_space import Candidate

    seen = {}

    class Wider(stages.Stage):
        name = "wider arx"

        def run(self, search, context):
            seen.update(delays=list(context.delays), orders=list(context.orders))
            na, nb, nk = context.orders[0]
            wider = Candidate("arx", {"na": na + 5, "nb": nb, "nk": nk, "center": True})
            search.run(self.name, [wider], False)

    wider = (*stages.STAGES[:2], Wider())
    result = identify(dead_zone_record(400), structures=["arx"], effort=SMALL, jobs=1, stages=wider)
    assert seen["delays"] and seen["orders"]
    assert any(s.stage == "wider arx" for s in result.ranked + result.rejected)
    assert [s["stage"] for s in result.search["stages"]][-2:] == ["wider arx", "refit"]

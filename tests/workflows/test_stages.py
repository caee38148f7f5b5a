"""blockid.workflows.stages: the search's stages, each a class in STAGES, and what a
stage may afford."""

from __future__ import annotations

from blockid.workflows.identify import EFFORTS, identify

from reference import SMALL, dead_zone_record, fourth_order_arx_halves


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


def _finalists_after(chain_orders, structures=("arx", "hammerstein")):
    """identify on an ARX plant of four poles with one chain scored beside the ARX
    models (``chain_orders``: its na, nb, nk), then the finalists stage."""
    from blockid.workflows import stages
    from blockid.workflows.search_space import Candidate

    class OneChain(stages.Stage):
        name = "one chain"

        def run(self, search, context):
            na, nb, nk = chain_orders
            chain = {"na": na, "nb": nb, "nk": nk, "input_block": "polynomial:degree=3",
                     "max_nfev": 5, "tail_fraction": 0.0}  # fmt: skip
            search.run(self.name, [Candidate("hammerstein", chain)], True)

    data, _ = fourth_order_arx_halves()
    plan = (*stages.STAGES[:2], OneChain(), stages.Finalists())
    return identify(data, structures=list(structures), effort=SMALL, jobs=1, stages=plan)


def test_a_finalist_far_behind_the_best_model_is_not_fitted_again():
    """A chain of one pole on a plant of four is more than FINALIST_REACH times the ARX
    model's error: the finalists stage fits nothing and the record says which and why;
    the chain of the plant's own orders, within reach, is fitted again."""
    from blockid.workflows.stages import FINALIST_REACH

    far = _finalists_after((1, 1, 1))
    chain = next(s for s in far.ranked if s.candidate.structure == "hammerstein")
    best = far.ranked[0]
    assert best.candidate.structure == "arx" and chain.rmse > FINALIST_REACH * best.rmse
    assert not any(s.stage == "finalists" for s in far.ranked + far.rejected)
    assert [f["label"] for f in far.search["out_of_reach"]] == [chain.candidate.label]
    assert any("not fitted again" in n for n in far.notes)

    near = _finalists_after((4, 2, 1))
    assert near.search["out_of_reach"] == []
    assert any(s.stage == "finalists" for s in near.ranked + near.rejected)


def test_a_model_that_may_not_be_chosen_leaves_every_finalist_in_reach():
    """Asked for chains only, the ARX models that guide the search (scored, never chosen)
    do not set the reach: the one chain is fitted again however far behind them."""
    chains_only = _finalists_after((1, 1, 1), structures=("hammerstein",))
    assert chains_only.search["out_of_reach"] == []
    assert chains_only.selected.stage == "finalists"

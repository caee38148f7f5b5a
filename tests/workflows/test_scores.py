"""blockid.workflows.scores: what identify scores and returns."""

from __future__ import annotations

from blockid.workflows.identify import identify

from reference import SMALL, dead_zone_record


def test_the_tables_list_candidates_by_their_score_and_keep_the_chosen_one():
    """The candidate tables once said "best first" and listed the choice's order (the
    fewer parameters first among near-ties): 0.0009372 shown third, after 0.0009386.
    Now by cross-validated RMSE, lowest first, the selected one kept."""
    result = identify(dead_zone_record(500), structures=["arx", "hammerstein"], effort=SMALL,
                      jobs=1)  # fmt: skip
    for n in (3, len(result.ranked)):
        rows = result.best_scored(n)
        scores = [s.rmse for s in rows[:n]]
        assert scores == sorted(scores) and result.selected in rows
        best = sorted(s.rmse for s in result.ranked)[: min(n, len(result.ranked))]
        assert scores[: len(best)] == best

"""Dispatch: which module takes an order and in which state the object is put down. Bids
and the auction's choice (`Bid`, `choose`, modelled floor time), the twin's ranked states
(`rank_states`, from a study or virtual experiments), what the floor's own transfers teach
(`posterior`, `rerank`, `fallback`: Beta–binomial per leg and state) and the KPIs of the
operations (`kpis`). Pure functions; the TMS's role calls them.
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.dispatch._auction import (
        DOCK_S,
        TRANSFER_S,
        Bid,
        choose,
        drive_s,
        estimate,
        floor_seconds,
    )
    from transfertwin.cps.dispatch._kpis import UNIT_STEPS, is_fault, kpis, with_calibration
    from transfertwin.cps.dispatch._learn import (
        FACE_POOL,
        LEGS,
        PRIOR_RUNS,
        fallback,
        posterior,
        record,
        rerank,
        state_key,
        tries,
        twin_priors,
        uninformed,
    )
    from transfertwin.cps.dispatch._needs import object_needs
    from transfertwin.cps.dispatch._orders import OrderBook, order_view
    from transfertwin.cps.dispatch._predict import (
        DEFAULT_STATE,
        ON_THE_FLY_THETA_STEP,
        StatePrediction,
        campaign_advice,
        campaign_predictions,
        learning_alone_states,
        rank_states,
        study_predictions,
        twin_words,
        virtual_predictions,
    )
    from transfertwin.study.adaptive import ADAPTIVE_MAX_FACTOR, adaptive_options

__all__ = [
    "ADAPTIVE_MAX_FACTOR",
    "DEFAULT_STATE",
    "DOCK_S",
    "FACE_POOL",
    "LEGS",
    "ON_THE_FLY_THETA_STEP",
    "PRIOR_RUNS",
    "TRANSFER_S",
    "UNIT_STEPS",
    "Bid",
    "OrderBook",
    "StatePrediction",
    "adaptive_options",
    "campaign_advice",
    "campaign_predictions",
    "choose",
    "drive_s",
    "estimate",
    "fallback",
    "floor_seconds",
    "is_fault",
    "kpis",
    "learning_alone_states",
    "object_needs",
    "order_view",
    "posterior",
    "rank_states",
    "record",
    "rerank",
    "state_key",
    "study_predictions",
    "tries",
    "twin_priors",
    "twin_words",
    "uninformed",
    "virtual_predictions",
    "with_calibration",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)

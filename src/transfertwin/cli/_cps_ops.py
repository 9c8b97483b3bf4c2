"""`transfertwin cps orders|kpis|query`: a floor's order queue and its KPIs, as the TMS
keeps them (docs/architecture.md, "Operation"), and a read-only SPARQL query to its
knowledge graph."""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time

from transfertwin._errors import InputError
from transfertwin.cli._cps_client import add_access, call_asset, floor_access, text_table

__all__ = ["cmd_kpis", "cmd_orders", "cmd_query", "kpi_lines", "register"]


def _ask(args: argparse.Namespace, op: str) -> object:
    where, info, creds = floor_access(args)
    try:
        return json.loads(asyncio.run(call_asset(info, creds, "TMS", op, timeout_s=10)))
    except (OSError, TimeoutError, ConnectionError) as exc:
        raise InputError(f"{where}: the TMS is not answering ({type(exc).__name__})") from None


def cmd_orders(args: argparse.Namespace) -> int:
    """List the order queue: every order with its state and, when it failed, the reason."""
    orders = _ask(args, "Orders")
    if args.json:
        print(json.dumps(orders, indent=2))
        return 0
    rows = [{**o, "submitted": time.strftime("%H:%M:%S", time.localtime(o["submitted"])),
             "source": o["source"] or "", "module": o["module"] or "",
             "to": o["destination"] + (f" ({o['target']})" if o["target"] not in
                                       (None, o["destination"]) else ""),
             "state": o["state"] + (f": {o['reason']}" if o.get("reason") else ""),
             "loaded": "/".join(str(v) for v in (o.get("loaded_state") or {}).values())}
            for o in orders]  # fmt: skip
    cols = ("operation", "object", "source", "to", "module", "loaded", "submitted", "state")
    print(text_table(rows, cols) if rows else "no orders yet")
    return 0


def _calibration_cost(args: argparse.Namespace, k: dict) -> dict:
    """The KPIs with the floor time of the Experiment Manager's calibration campaigns
    counted (`with_calibration`); as they were when the floor has no EM or it does not
    answer (said on stderr)."""
    from transfertwin.cps.dispatch import with_calibration

    where, info, creds = floor_access(args)
    ems = [a["id"] for a in info["assets"]
           if a.get("role_class", a.get("class")) == "experiment_manager"]  # fmt: skip
    if not ems:
        return k
    try:
        st = json.loads(asyncio.run(call_asset(info, creds, ems[0], "CampaignStatus",
                                               timeout_s=10)))  # fmt: skip
    except Exception as exc:  # the KPIs stand without it
        print(f"{where}: the Experiment Manager did not say its campaigns' floor time "
              f"({type(exc).__name__}); KPIs without it", file=sys.stderr)  # fmt: skip
        return k
    return with_calibration(k, float(st.get("floor_s_all") or 0.0),
                            len(k["utilisation"]["modules"]))


def kpi_lines(k: dict) -> list[str]:
    """The KPIs `k` (the TMS's ``Kpis``, with the campaigns' cost) as `cps kpis` prints
    them. Faults (a module lost mid-operation, an error) are no transfer outcomes: they
    are counted on a line of their own and are in neither the failures nor the share."""
    low, high = k["success_share_ci95"]
    share = ("n/a" if k["success_share"] is None else
             f"{k['success_share']:.3f} [{low:.3f}, {high:.3f}] (Clopper-Pearson 95 %)")
    lead = k["mean_lead_time_s"]
    lines = [f"policy {k['policy']}: {k['orders']} orders, {k['delivered']} delivered, "
             f"{k['failed']} failed, {k.get('faults', 0)} faults, {k['in_progress']} in progress",
             f"operations per hour {k['operations_per_hour']:.1f} (wall clock); per floor hour "
             f"{k['operations_per_floor_hour'] or 0:.1f} (modelled)",
             f"success share {share}; mean lead time {'n/a' if lead is None else f'{lead:.1f} s'}"]
    for kind in ("modules", "units"):
        util = ", ".join(f"{a} {u:.0%}" for a, u in k["utilisation"][kind].items())
        lines.append(f"utilisation of the {kind}: {util}")
    reasons = ", ".join(f"{r}: {n}" for r, n in k["failed_by_reason"].items()) or "none"
    lines.append(f"failed by reason: {reasons}")
    if k.get("faults"):
        faults = ", ".join(f"{r}: {n}" for r, n in k.get("faults_by_reason", {}).items())
        lines.append(f"faults (not transfer outcomes, not in the share): {faults}")
    if k.get("calibration_floor_s"):
        per = k["operations_per_floor_hour_with_calibration"]
        lines.append(f"calibration campaigns: {k['calibration_floor_s']:.0f} s of floor time; "
                     f"per floor hour with it {per or 0:.1f}")  # fmt: skip
    if k.get("predictions_unanswered"):
        lines.append("orders planned without a prediction (the Experiment Manager did not "
                     f"answer): {k['predictions_unanswered']}")
    return lines


def cmd_kpis(args: argparse.Namespace) -> int:
    """Print the floor's KPIs (operations per hour, success share and its interval, lead
    time, utilisation, failures by reason, faults apart)."""
    k = _calibration_cost(args, _ask(args, "Kpis"))
    if args.json:
        print(json.dumps(k, indent=2))
        return 0
    print("\n".join(kpi_lines(k)))
    return 0


def _first_line(text: str) -> str:
    return (text.strip().splitlines() or [""])[0][:300]


def cmd_query(args: argparse.Namespace) -> int:
    """Ask the knowledge graph a SPARQL SELECT query (its ``Query`` operation, which a
    viewer may call; prefixes tt, rdf, rdfs predeclared). The graph answers SELECT only:
    an update, a CONSTRUCT or a query it cannot parse is refused with its reason (exit 2)."""
    from transfertwin.cps.opcua import OperationRefused

    where, info, creds = floor_access(args)
    # the least role that may: a viewer (an operator credential from another host)
    role = "viewer" if creds is not None and "viewer" in creds.users else "operator"
    try:
        text = asyncio.run(call_asset(info, creds, "KG", "Query", args.sparql, timeout_s=10,
                                      role=role))  # fmt: skip
    except OperationRefused as exc:
        raise InputError(f"the knowledge graph refused the query: "
                         f"{_first_line(exc.reason)}") from None  # fmt: skip
    except (OSError, TimeoutError, ConnectionError) as exc:
        raise InputError(f"{where}: the knowledge graph is not answering "
                         f"({type(exc).__name__})") from None  # fmt: skip
    rows = json.loads(text)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    cols = tuple(dict.fromkeys(k for row in rows for k in row))
    print(text_table(rows, cols) if rows else "no solutions")
    return 0


def register(csub: argparse._SubParsersAction) -> None:
    """Add `cps orders`, `cps kpis` and `cps query`."""
    for name, func, text in (("orders", cmd_orders, "the order queue with each order's state"),
                             ("kpis", cmd_kpis, "operations per hour, success share, lead "
                                                "time, utilisation, failures by reason")):
        p = csub.add_parser(name, help=text)
        add_access(p)
        p.add_argument("--json", action="store_true", help="one JSON document")
        p.set_defaults(func=func)
    p = csub.add_parser("query", help="ask the knowledge graph a SPARQL SELECT query "
                        "(read-only; prefixes tt, rdf, rdfs predeclared)")  # fmt: skip
    p.add_argument("sparql", metavar="SPARQL",
                   help="e.g. 'SELECT ?id WHERE { ?a tt:assetId ?id }'")  # fmt: skip
    add_access(p)
    p.add_argument("--json", action="store_true",
                   help="the solutions as JSON: one object per row, variable -> value")  # fmt: skip
    p.set_defaults(func=cmd_query)

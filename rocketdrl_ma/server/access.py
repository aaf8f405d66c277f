"""Zenoh authentication and access control generated from the server's ``access`` settings.

The rules (default deny; ``R`` is ``rocketdrl/<server>``):

- every user: everything on its own prefix ``R/u/<user>/**`` (its lobby queries and their replies, its
  slots' observations, actions, errors and liveliness tokens, a league bot's invitation queryable, its
  training runs' broadcast); subscribing to the public ``R/match/*/state`` and ``R/match/*/events``;
  fetching ``R/key``; watching the server's liveliness token ``R/alive`` and every user's training runs
  ``R/u/*/train/**``;
- ``admin`` users also: querying any user's ``R/u/*/invite`` (the league invites its remote entrants);
- the user ``server`` (the match server as a client of a router): everything under ``R/**``;
- the user ``members``, as whom every member the server manages connects (``members.py``): what every user
  may, and everything on ``R/u/*/**`` but the prefixes of the users above (a deny rule, which Zenoh applies
  before any allow rule). The transport cannot tell one member from another: the server checks each member's
  signature wherever it matters.

Zenoh applies them to the connections of the session holding them: the server's own (it is a peer,
bots connect as clients) or a router's. Peers that connect to each other directly bypass them
(eclipse-zenoh/zenoh#2137): bots and spectators must be clients.
"""
from __future__ import annotations

import secrets
from pathlib import Path

from rocketdrl_ma.validation import check_name
from .settings import MEMBERS_USER, SERVER_USER

ALL_MESSAGES = ["put", "delete", "declare_subscriber", "query", "reply", "declare_queryable",
                "liveliness_token", "liveliness_query", "declare_liveliness_subscriber"]
BOTH = ["ingress", "egress"]


def read_users_file(path: str | Path) -> dict[str, str]:
    """``user:password`` lines (Zenoh's usrpwd dictionary) -> ``{user: password}``."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"access.users_file: no such file {str(path)!r} (`rocketdrl-ma keys` writes it)")
    users: dict[str, str] = {}
    for n, line in enumerate(p.read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        user, sep, password = line.partition(":")
        if not sep or not password:
            raise ValueError(f"access.users_file: line {n} is not 'user:password'")
        users[check_name(f"access.users_file line {n}", user)] = password
    return users


def add_missing_users(path: str | Path, users: list[str]) -> list[str]:
    """Give every user of ``users`` without a password in ``path`` a random one (the file is created readable by
    its owner only); the users added."""
    from .crypto import append_private
    p = Path(path)
    existing = read_users_file(p) if p.is_file() else {}
    missing = [u for u in users if u not in existing]
    if missing:
        append_private(p, "".join(f"{u}:{secrets.token_urlsafe(24)}\n" for u in missing).encode())
    return missing


def acl_config(server: str, roles: dict[str, str], router: bool = False) -> dict:
    """Zenoh's ``access_control`` section for ``server`` and ``{user: role}`` (``router``: the server is the
    router's client ``server`` and needs everything under its root), with the ``members`` user of the members
    the server manages."""
    root = f"rocketdrl/{check_name('server', server)}"

    def allow(rule_id: str, flows: list[str], messages: list[str], *keys: str) -> dict:
        return {"id": rule_id, "permission": "allow", "flows": flows, "messages": messages, "key_exprs": list(keys)}

    public = (f"{root}/match/*/state", f"{root}/match/*/events")
    rules = [
        allow("public_subscribe", ["ingress"], ["declare_subscriber"], *public),
        allow("public_data", ["egress"], ["put"], *public),
        allow("key_query", ["ingress"], ["query"], f"{root}/key"),
        allow("key_reply", ["egress"], ["reply"], f"{root}/key"),
        allow("alive_watch", ["ingress"], ["declare_liveliness_subscriber", "liveliness_query"], f"{root}/alive"),
        allow("alive_token", ["egress"], ["liveliness_token"], f"{root}/alive"),
        allow("train_watch", ["ingress"], ["declare_subscriber", "declare_liveliness_subscriber", "liveliness_query"],
              f"{root}/u/*/train/**"),
        allow("train_data", ["egress"], ["put", "liveliness_token"], f"{root}/u/*/train/**"),
        allow("invite_query", ["ingress"], ["query"], f"{root}/u/*/invite"),
        allow("invite_reply", ["egress"], ["reply"], f"{root}/u/*/invite"),
    ]
    common = ["public_subscribe", "public_data", "key_query", "key_reply", "alive_watch", "alive_token", "train_watch",
              "train_data"]
    subjects: list[dict] = []
    policies: list[dict] = []
    for user in sorted(roles):
        rules.append(allow(f"own_{user}", BOTH, ALL_MESSAGES, f"{root}/u/{user}/**"))
        subjects.append({"id": f"user_{user}", "usernames": [user]})
        policy_rules = [*common, f"own_{user}"]
        if roles[user] == "admin":
            policy_rules += ["invite_query", "invite_reply"]
        policies.append({"id": f"policy_{user}", "rules": policy_rules, "subjects": [f"user_{user}"]})
    # members: every prefix the users above do not own (the server tells members apart by their signatures)
    rules.append(allow("members_own", BOTH, ALL_MESSAGES, f"{root}/u/*/**"))
    owned = sorted({*roles, SERVER_USER, MEMBERS_USER})
    rules.append({"id": "members_not_users", "permission": "deny", "flows": BOTH, "messages": ALL_MESSAGES,
                  "key_exprs": [f"{root}/u/{user}/**" for user in owned]})
    subjects.append({"id": "user_members", "usernames": [MEMBERS_USER]})
    policies.append({"id": "policy_members", "rules": [*common, "members_own", "members_not_users"],
                     "subjects": ["user_members"]})
    if router:
        rules.append(allow("match_server", BOTH, ALL_MESSAGES, f"{root}/**"))
        subjects.append({"id": "user_server", "usernames": [SERVER_USER]})
        policies.append({"id": "policy_server", "rules": ["match_server"], "subjects": ["user_server"]})
    return {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects,
            "policies": policies}

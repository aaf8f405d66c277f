"""``rocketdrl-ma keys CONFIG``: make what a server (or router) YAML names but lacks, never overwriting.

- the server's Ed25519 key (``<key_dir>/server.key``, ``server.pub``) and admin secret (``admin.secret``);
- ``access.users_file``: a random password for the users ``server`` and ``members`` (whom the members the server
  manages connect as: ``rocketdrl-ma users add``) and for every user in ``access.roles``;
- TLS, for the process that listens (the server in peer mode, or the router): a CA (``<key_dir>/tls/ca.pem``,
  its key beside it) and a certificate for ``--tls-host`` names/addresses at the paths its ``zenoh.tls``
  names (``listen_certificate``, ``listen_private_key``);
- one client YAML per user (``<key_dir>/clients/<user>.yaml``): the endpoint, the user's password, the CA,
  the server's key to pin (and, for admins, the admin secret). Hand each user their own file.

Every secret file is created readable by its owner only. Nothing here is meant to be committed.
"""
from __future__ import annotations

import base64
import datetime
import ipaddress
import secrets
from pathlib import Path

import yaml

from rocketdrl_ma.config import load_yaml_mapping

from .crypto import ServerIdentity, load_or_create_secret, write_private
from .router import RouterSettings
from .settings import MEMBERS_USER, SERVER_USER, ServerSettings, ZenohSettings, _endpoint_host, is_encrypted_endpoint

CERT_DAYS = 825


def _server_and_listener(config: str) -> tuple[ServerSettings, ZenohSettings]:
    raw = load_yaml_mapping(config, "config")
    if "serves" in raw:  # a router YAML: the server's users, the router's TLS
        router = RouterSettings.from_dict(raw)
        if router.serves is None:
            raise ValueError("serves: the router YAML names no server YAML")
        return router.serves, router.zenoh
    server = ServerSettings.from_dict(raw)
    return server, server.zenoh


def _ca(tls_dir: Path, made: list[str]):
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    ca_pem, ca_key = tls_dir / "ca.pem", tls_dir / "ca.key"
    if ca_pem.is_file() and ca_key.is_file():
        key = serialization.load_pem_private_key(ca_key.read_bytes(), password=None)
        return x509.load_pem_x509_certificate(ca_pem.read_bytes()), key
    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, f"rocketdrl-ma CA {secrets.token_hex(4)}")])
    now = datetime.datetime.now(datetime.timezone.utc)
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
            .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=CERT_DAYS))
            .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
            .add_extension(x509.KeyUsage(False, False, False, False, False, True, True, False, False), critical=True)
            .sign(key, hashes.SHA256()))
    write_private(ca_key, key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                            serialization.NoEncryption()))
    ca_pem.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    made.append(f"TLS CA: {ca_pem} (its key {ca_key})")
    return cert, key


def _leaf(ca_cert, ca_key, hosts: list[str], cert_path: Path, key_path: Path, made: list[str]) -> None:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    names: list[x509.GeneralName] = []
    for host in hosts:
        try:
            names.append(x509.IPAddress(ipaddress.ip_address(host)))
        except ValueError:
            names.append(x509.DNSName(host))
    key = ec.generate_private_key(ec.SECP256R1())
    now = datetime.datetime.now(datetime.timezone.utc)
    cert = (x509.CertificateBuilder().subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, hosts[0])]))
            .issuer_name(ca_cert.subject).public_key(key.public_key()).serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5)).not_valid_after(now + datetime.timedelta(days=CERT_DAYS))
            .add_extension(x509.SubjectAlternativeName(names), critical=False)
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
            .add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH]), critical=False)
            .sign(ca_key, hashes.SHA256()))
    write_private(key_path, key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                              serialization.NoEncryption()))
    cert_path.parent.mkdir(parents=True, exist_ok=True)
    cert_path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    made.append(f"TLS certificate for {hosts}: {cert_path} (key {key_path})")


def _users_file(path: Path, users: list[str], made: list[str]) -> dict[str, str]:
    from .access import add_missing_users, read_users_file
    missing = add_missing_users(path, users)
    if missing:
        made.append(f"passwords for {missing} in {path}")
    return read_users_file(path)


def make_keys(config: str, tls_hosts: list[str] | None = None, connect: list[str] | None = None,
              clients_dir: str | None = None) -> list[str]:
    """Create whatever is missing (see the module docstring); one line per thing made or found."""
    server, listener = _server_and_listener(config)
    made: list[str] = []
    key_dir = server.keys_path
    had_key = (key_dir / "server.key").is_file()
    identity = ServerIdentity.load_or_create(key_dir / "server.key")
    made.append(f"server key {identity.public_text} ({'kept' if had_key else 'made'}: {key_dir / 'server.key'})")
    had_admin = (key_dir / "admin.secret").is_file()
    admin_secret = load_or_create_secret(key_dir / "admin.secret")
    made.append(f"admin secret {'kept' if had_admin else 'made'}: {key_dir / 'admin.secret'}")
    listen = [e for e in listener.listen_endpoints() if is_encrypted_endpoint(e)]
    ca_cert = None
    cert_path, key_path = listener.tls.get("listen_certificate"), listener.tls.get("listen_private_key")
    if cert_path and key_path:
        from cryptography.hazmat.primitives import serialization
        ca_cert, ca_key = _ca(key_dir / "tls", made)
        if not Path(cert_path).is_file():
            hosts = tls_hosts or sorted({_endpoint_host(e) for e in listen}) or ["localhost"]
            _leaf(ca_cert, ca_key, hosts, Path(cert_path), Path(key_path), made)
        ca_b64 = base64.b64encode(ca_cert.public_bytes(serialization.Encoding.PEM)).decode()
    elif listen:
        made.append("no TLS certificate made: the listening zenoh.tls names no listen_certificate/listen_private_key")
    if not server.access.enabled:
        made.append("no users: the config has no access section (the open mode)")
        return made
    users = _users_file(server.users_path, [SERVER_USER, MEMBERS_USER, *sorted(server.access.roles)], made)
    out = Path(clients_dir) if clients_dir else key_dir / "clients"
    endpoints = connect or listen or list(listener.listen_endpoints())
    for user, role in sorted(server.access.roles.items()):
        path = out / f"{user}.yaml"
        if path.is_file():
            continue
        zenoh: dict = {"mode": "client", "connect": list(endpoints), "auth": {"user": user, "password": users[user]}}
        if ca_cert is not None:
            zenoh["tls"] = {"root_ca_certificate_base64": ca_b64}
        client = {"server": server.name, "server_key": identity.public_text, "zenoh": zenoh}
        if role == "admin":
            client["admin_secret"] = admin_secret.hex()
        use = {"admin": f"rocketdrl-ma lobby create matches/1v1.yaml --id M --config {path.name}",
               "player": f"rocketdrl-ma bot --config {path.name} --policy scripted:ball_chaser --match M --ticket T",
               "spectator": f"rocketdrl-ma watch M --config {path.name}"}[role]
        header = f"# {user} ({role}) on match server {server.name!r}: a private file, for {user} only.\n# {use}\n"
        write_private(path, (header + yaml.safe_dump(client, sort_keys=False)).encode())
        made.append(f"client config for {user} ({role}): {path}")
    return made

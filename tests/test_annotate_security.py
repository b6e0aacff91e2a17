"""Security of the annotation server, one test per rule (issue 15 item 6)."""

from __future__ import annotations

import httpx
import pytest
from annotate_util import numbered_video, running
from typer.testing import CliRunner


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    return numbered_video(tmp_path_factory.mktemp("v") / "v.mp4", 20)


@pytest.fixture
def server(video, tmp_path):
    ann = tmp_path / "ann.json"
    with running([video], ann, max_body=64 << 10) as url:
        c = httpx.Client(base_url=url, timeout=30)
        html = c.get("/").text
        token = html.split('name="vidstyle-token" content="')[1].split('"')[0]
        yield c, url, token, ann
        c.close()


def _put(c, url, token, **kw):
    headers = {"Origin": url, "X-Vidstyle-Token": token, **kw.pop("headers", {})}
    return c.put("/api/annotations", headers=headers, **kw)


BODY = {"revision": 0, "videos": [{"id": "0", "transitions": [], "segments": [{"start": 0, "end": 3, "action": "Jab"}]}]}


def test_listens_on_loopback_by_default(server):
    c, url, token, ann = server
    assert url.startswith("http://127.0.0.1:")


def test_host_other_than_loopback_warns(video, tmp_path, monkeypatch):
    from vidstyle.annotate import server as srv
    from vidstyle.cli import app

    seen = {}
    monkeypatch.setattr(srv, "serve", lambda session, host, port, open_browser: seen.update(host=host))
    res = CliRunner().invoke(app, ["annotate", str(video), "-a", str(tmp_path / "a.json"), "--host", "0.0.0.0",
                                   "--no-browser"])
    assert res.exit_code == 0, res.output
    assert seen["host"] == "0.0.0.0" and "listening on 0.0.0.0" in " ".join(res.output.split())
    res = CliRunner().invoke(app, ["annotate", str(video), "-a", str(tmp_path / "a.json"), "--no-browser"])
    assert res.exit_code == 0 and seen["host"] == "127.0.0.1" and "listening on" not in res.output


def test_foreign_host_header_is_refused(server):
    c, url, token, ann = server
    port = url.rsplit(":", 1)[1]
    for host in ("evil.example", f"evil.example:{port}", "127.0.0.1:1", ""):
        r = c.get("/api/videos", headers={"Host": host})
        assert r.status_code == 400 and "Host" in r.json()["error"]
        r = c.get("/api/videos/0/frames/0", headers={"Host": host})
        assert r.status_code == 400
    for host in (f"127.0.0.1:{port}", f"localhost:{port}"):
        assert c.get("/api/videos", headers={"Host": host}).status_code == 200


def test_state_change_needs_token_and_origin(server):
    c, url, token, ann = server
    assert _put(c, url, "", json=BODY).status_code == 403
    assert _put(c, url, "x" * len(token), json=BODY).status_code == 403
    assert c.put("/api/annotations", json=BODY, headers={"X-Vidstyle-Token": token}).status_code == 403  # no Origin
    assert _put(c, url, token, json=BODY, headers={"Origin": "http://evil.example"}).status_code == 403
    assert c.post("/api/import/native?video=0", content=b"{}", headers={"Origin": url}).status_code == 403
    assert not ann.exists()
    assert _put(c, url, token, json=BODY).status_code == 200 and ann.exists()


def test_only_given_videos_by_id_and_no_request_becomes_a_path(server, video):
    c, url, token, ann = server
    for path in ("/api/videos/1/frames/0", "/api/videos/..%2Fv.mp4/frames/0", f"/api/videos/{video}/frames/0",
                 "/api/videos/0/frames/..%2F..%2Fetc%2Fpasswd", "/static/..%2F__init__.py", "/static/index.html",
                 "/static/%2Fetc%2Fpasswd", "/api/export/native?video=../x", "/etc/passwd", "/static/../server.py"):
        r = c.get(path)
        assert r.status_code in (400, 404), path
        assert b"import" not in r.content and b"root:" not in r.content
    assert c.get("/static/app.js").status_code == 200
    assert c.get("/api/export/..%2F..%2Fx?video=0").status_code in (400, 404)


def test_request_size_limit(server):
    c, url, token, ann = server
    big = b'{"revision": 0, "videos": [], "pad": "' + b"x" * (70 << 10) + b'"}'
    r = _put(c, url, token, content=big, headers={"Content-Type": "application/json"})
    assert r.status_code == 413
    # a chunked body without Content-Length is counted too
    r = _put(c, url, token, content=iter([big[i:i + 4096] for i in range(0, len(big), 4096)]),
             headers={"Content-Type": "application/json"})
    assert r.status_code == 413
    assert not ann.exists()


def test_bad_json_is_a_4xx_with_message_and_changes_nothing(server):
    c, url, token, ann = server
    assert _put(c, url, token, json=BODY).status_code == 200
    before = ann.read_bytes()
    for junk in (b"", b"{", b"null", b"[]", b'{"revision": "1"}', b'{"revision": 1, "videos": 5}',
                 b'{"revision": 1, "videos": [{"id": "0", "segments": [{"start": 5, "end": 2, "action": "Jab"}]}]}'):
        r = _put(c, url, token, content=junk, headers={"Content-Type": "application/json"})
        assert 400 <= r.status_code < 500 and r.json()["error"], junk
    assert ann.read_bytes() == before
    assert c.get("/api/annotations").json()["revision"] == 1


def test_page_carries_token_and_a_strict_csp(server):
    c, url, token, ann = server
    r = c.get("/")
    assert token in r.text and len(token) >= 32
    csp = r.headers["content-security-policy"]
    assert "script-src 'self'" in csp and "frame-ancestors 'none'" in csp
    # each server start makes a new token
    assert c.get("/api/annotations").status_code == 200


# ------------------------------------------------------------------ beyond loopback: a secret (issue 33 item 5)
SECRET = "k3y-" + "s" * 28
API = ["/api/videos", "/api/annotations", "/api/videos/0/frames/0", "/api/videos/0/timestamps",
       "/api/videos/0/overlays", "/api/export/native?video=0"]


@pytest.fixture
def keyed(video, tmp_path):
    from annotate_util import session

    from vidstyle.annotate.server import Running

    s = session([video], tmp_path / "ann.json", max_body=64 << 10)
    s.secret = SECRET  # as launch sets it for a --host beyond loopback
    with Running(s) as url:
        c = httpx.Client(base_url=url, timeout=30)
        yield c, url, s.token, tmp_path / "ann.json"
        c.close()


def test_beyond_loopback_every_api_request_needs_the_secret(keyed):
    c, url, token, ann = keyed
    seen = []
    for path in API:
        for headers in ({}, {"X-Vidstyle-Secret": "wrong"}, {"X-Vidstyle-Secret": SECRET[:-1]}):
            r = c.get(path, headers=headers)
            assert r.status_code == 401 and "key" in r.json()["error"], path
            seen.append(r)
        r = c.get(path, headers={"X-Vidstyle-Secret": SECRET})
        assert r.status_code == 200, path
        sep = "&" if "?" in path else "?"
        assert c.get(f"{path}{sep}key={SECRET}").status_code == 200  # image and download URLs carry it
        assert c.get(f"{path}{sep}key=nope").status_code == 401
        seen.append(r)
    assert _put(c, url, token, json=BODY).status_code == 401 and not ann.exists()  # token + Origin: not enough
    r = _put(c, url, token, json=BODY, headers={"X-Vidstyle-Secret": SECRET})
    assert r.status_code == 200 and ann.exists()
    r = c.post("/api/import/native?video=0", content=b"{}", headers={"Origin": url, "X-Vidstyle-Token": token})
    assert r.status_code == 401
    # the page and its script load without it (the page takes the key from the URL fragment) and never hold it
    for path in ("/", "/static/app.js", "/static/style.css"):
        r = c.get(path)
        assert r.status_code == 200
        seen.append(r)
    for r in seen:
        assert SECRET not in r.text and SECRET not in str(r.headers)


def test_the_secret_is_printed_once_at_start_and_only_beyond_loopback(video, tmp_path, monkeypatch, capsys):
    import uvicorn

    from vidstyle.annotate import server as srv
    from vidstyle.cli import app

    sessions = []
    monkeypatch.setattr(srv, "serve", lambda session, host, port, open_browser: sessions.append(session))
    for host in ("0.0.0.0", "192.0.2.7", "::"):
        res = CliRunner().invoke(app, ["annotate", str(video), "-a", str(tmp_path / "a.json"), "--host", host,
                                       "--no-browser"])
        assert res.exit_code == 0, res.output
        assert sessions[-1].secret and len(sessions[-1].secret) >= 32
    assert len({s.secret for s in sessions}) == 3  # a new one per start
    for host in ("127.0.0.1", "localhost", "::1", "127.0.0.5"):
        res = CliRunner().invoke(app, ["annotate", str(video), "-a", str(tmp_path / "a.json"), "--host", host,
                                       "--no-browser"])
        assert res.exit_code == 0 and sessions[-1].secret is None  # loopback: as before, no secret
    monkeypatch.undo()
    monkeypatch.setattr(uvicorn.Server, "run", lambda self, sockets=None: None)
    keyed = sessions[0]
    capsys.readouterr()
    srv.serve(keyed, "127.0.0.1", 0, open_browser=False)
    out = capsys.readouterr()
    assert out.err.count(keyed.secret) == 1 and f"#key={keyed.secret}" in out.err and keyed.secret not in out.out
    srv.serve(sessions[-1], "127.0.0.1", 0, open_browser=False)
    assert "#key=" not in capsys.readouterr().err

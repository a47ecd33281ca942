"""What the checker knows after it has accepted a program: POUs, variables, globals, tasks, located cells."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from . import types as T
from .ast import Pos


@dataclass(eq=False)
class Var:
    name: str                  # as declared
    key: str                   # upper case
    ty: T.Type
    kind: str                  # VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_EXTERNAL VAR_GLOBAL RESULT
    pos: Pos
    constant: bool = False
    init: Any = None           # AST of the initial value, or None
    location: str | None = None
    pou: Any = None            # the PouSym that declares it, None for a global
    scope: Any = None          # ConfigSym or ResourceSym for a global
    implicit: bool = False     # EN / ENO

    @property
    def is_fb_instance(self) -> bool:
        return isinstance(self.ty, T.PouType)


@dataclass(eq=False)
class PouSym:
    name: str
    key: str
    kind: str                  # FUNCTION FUNCTION_BLOCK PROGRAM
    pos: Pos
    ast: Any
    std: bool = False
    vars: dict[str, Var] = field(default_factory=dict)   # every variable, by key, declaration order
    params: list[Var] = field(default_factory=list)      # formal parameters: inputs, in-outs, outputs
    return_type: T.Type | None = None
    result: Var | None = None  # a FUNCTION's result variable (its own name)
    ty: T.PouType | None = None
    callees: set = field(default_factory=set)            # POUs whose bodies this one calls or instantiates
    checked: bool = False
    no_code: bool = False      # declared between {disable code generation} and {enable code generation}

    def layout(self) -> list[Var]:
        """Struct members in C order (FB/PROGRAM): EN, ENO, the interface, then the private variables."""
        vs = list(self.vars.values())
        iface = [v for v in vs if v.kind in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and not v.implicit]
        private = [v for v in vs if v.kind in ("VAR", "VAR_TEMP", "VAR_EXTERNAL")]
        implicit = [v for v in vs if v.implicit]
        return implicit + iface + private

    @property
    def externals(self) -> list[Var]:
        return [v for v in self.vars.values() if v.kind == "VAR_EXTERNAL"]

    @property
    def instances(self) -> list[Var]:
        return [v for v in self.vars.values() if v.kind in ("VAR", "VAR_TEMP") and v.is_fb_instance]


@dataclass(eq=False)
class TaskSym:
    name: str
    key: str
    pos: Pos
    interval_ns: int | None
    priority: int = 0


@dataclass(eq=False)
class ProgInst:
    name: str
    key: str
    pos: Pos
    pou: PouSym
    task: TaskSym | None


@dataclass(eq=False)
class ResourceSym:
    name: str
    key: str
    pos: Pos
    globals: dict[str, Var] = field(default_factory=dict)
    tasks: list[TaskSym] = field(default_factory=list)
    programs: list[ProgInst] = field(default_factory=list)
    config: Any = None
    implicit: bool = False     # written without RESOURCE: left out of the variables' paths, as MatIEC does

    @property
    def described(self) -> str:
        return "the configuration" if self.implicit else f"resource {self.name}"

    def path(self) -> str:
        """The prefix of the paths of its program instances and globals."""
        return self.config.key if self.implicit else f"{self.config.key}.{self.key}"


@dataclass(eq=False)
class ConfigSym:
    name: str
    key: str
    pos: Pos
    globals: dict[str, Var] = field(default_factory=dict)
    resources: list[ResourceSym] = field(default_factory=list)


@dataclass(eq=False)
class LocatedCell:
    """Storage of a directly represented variable (%IX0.1), defined by the generated code."""
    location: str              # %IX0.1 (upper case)
    ty: T.Type
    pos: Pos

    @property
    def cname(self) -> str:
        return "__LOC_" + self.location[1:].replace(".", "_")


@dataclass
class Program:
    """A checked compilation unit: everything the code generator needs."""
    types: list[T.Type]                     # named and anonymous derived types, in declaration order
    pous: list[PouSym]                      # in declaration order (standard FBs where first used)
    config: ConfigSym | None
    located: dict[str, LocatedCell]
    files: list[str]

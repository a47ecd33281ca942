"""The layout of iec2c's C, described for the harness: the manifest and `plc_tables.c`.

iec2c writes POUS.h (types, FB and program structs), Config0.c / Res*.c (globals, program instances),
VARIABLES.csv (program instances, tick) and LOCATED_VARIABLES.h (located variables). From them this
module generates `plc_tables.c` (located storage, `plc_root_addr`, `plc_type_size`) and the manifest
(docs/architecture.md 1.1). LOCATED_VARIABLES.h is parsed, never #included: MatIEC HEAD writes bare
VAR_GLOBAL names into it. iec2c's C loses array lower bounds and ST type names, which the declaration
scanner (st_decls) recovers from the sources.
"""

from __future__ import annotations

import csv
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..builtin.errors import BuiltinCompileError
from ..sources import Sources
from . import st_decls
from .tool import Matiec, MatiecError, run_iec2c

NAME = "matiec"
ELEMENTARY = {"BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD",
              "DWORD", "LWORD", "REAL", "LREAL", "TIME", "DATE", "TOD", "DT", "STRING"}

# ---- what the generated C declares ----------------------------------------------------------------------

@dataclass
class CTypes:
    arrays: dict[str, tuple[str, list[int]]] = field(default_factory=dict)     # name -> (base, sizes)
    enums: dict[str, list[str]] = field(default_factory=dict)
    structs: dict[str, list[tuple[str, str]]] = field(default_factory=dict)     # name -> [(ctype, member)]
    derived: dict[str, str] = field(default_factory=dict)
    pous: dict[str, list[tuple[str, str, str]]] = field(default_factory=dict)   # name -> [(how, ctype, member)]


_LINE_DIRECTIVE = re.compile(r"^\s*#line\b.*$", re.M)
_ARRAY = re.compile(r"__DECLARE_ARRAY_TYPE\(\s*(\w+)\s*,\s*(\w+)\s*,\s*((?:\[\s*\d+\s*\])+)\s*\)")
_ENUM = re.compile(r"__DECLARE_ENUMERATED_TYPE\(\s*(\w+)\s*,(.*?)\)", re.S)
_STRUCT = re.compile(r"__DECLARE_STRUCT_TYPE\(\s*(\w+)\s*,(.*?)\)", re.S)
_DERIVED = re.compile(r"__DECLARE_DERIVED_TYPE\(\s*(\w+)\s*,\s*(\w+)\s*\)")
_TYPEDEF_STRUCT = re.compile(r"typedef\s+struct\s*\{(.*?)\}\s*(\w+)\s*;", re.S)
_MEMBER_MACRO = re.compile(r"^__DECLARE_(VAR|EXTERNAL|LOCATED|EXTERNAL_FB)\(\s*(\w+)\s*,\s*(\w+)\s*\)$")
_MEMBER_PLAIN = re.compile(r"^(\w+)\s+(\w+)\s*;$")


def is_configuration_unit(path: Path) -> bool:
    """The unit iec2c names after the CONFIGURATION (Config0.c, Plant.c...): it defines config_init__."""
    return path.suffix == ".c" and path.name != "POUS.c" and "void config_init__(" in path.read_text()


def parse_header(text: str, into: CTypes | None = None, origin: str = "POUS.h") -> CTypes:
    ct = into or CTypes()
    text = _LINE_DIRECTIVE.sub("", text)
    text = re.sub(r"//[^\n]*", "", text)
    for name, base, sizes in _ARRAY.findall(text):
        ct.arrays[name] = (base, [int(s) for s in re.findall(r"\d+", sizes)])
    for name, body in _ENUM.findall(text):
        prefix = name + "__"
        ct.enums[name] = [v.strip()[len(prefix):] if v.strip().startswith(prefix) else v.strip()
                          for v in body.split(",") if v.strip()]
    for name, body in _STRUCT.findall(text):
        members = []
        for decl in body.split(";"):
            decl = decl.strip()
            if decl:
                m = _MEMBER_PLAIN.match(decl + ";")
                if not m:
                    raise MatiecError(f"{origin}: struct {name} has a member this backend does not "
                                      f"understand: {decl!r}")
                members.append((m[1], m[2]))
        ct.structs[name] = members
    for name, base in _DERIVED.findall(text):
        ct.derived[name] = base
    for body, name in _TYPEDEF_STRUCT.findall(text):
        members = []
        for raw in body.splitlines():
            line = raw.strip()
            if not line:
                continue
            m = _MEMBER_MACRO.match(line)
            if m:
                members.append((m[1], m[2], m[3]))
                continue
            m = _MEMBER_PLAIN.match(line)
            if m:
                members.append(("INSTANCE", m[1], m[2]))
                continue
            raise MatiecError(f"{origin}: POU {name} has a member this backend cannot describe: {line!r} "
                              f"(SFC steps and actions are not supported by the manifest)")
        ct.pous[name] = members
    return ct


@dataclass
class Root:
    path: str
    cname: str          # C symbol
    how: str            # GLOBAL | GLOBAL_LOCATED | GLOBAL_FB | PROGRAM | LOCATION
    ctype: str
    scope: str = ""     # ST scope of a global ("CONFIG0" / "CONFIG0.RES0")
    name: str = ""


_GLOBAL = re.compile(r"__DECLARE_GLOBAL(|_LOCATED|_FB)\(\s*(\w+)\s*,\s*(\w+)\s*,\s*(\w+)\s*\)")
_INSTANCE = re.compile(r"^(\w+)\s+(\w+?)__(\w+)\s*;\s*$", re.M)
_LOCATED = re.compile(r"__LOCATED_VAR\(\s*(\w+)\s*,\s*(\w+)\s*,\s*([IQM])\s*,\s*(\w)\s*,\s*([0-9,\s]*)\)")


def parse_roots(out_dir: Path, generated: list[Path], ctypes_: CTypes) -> tuple[list[Root], int]:
    configs = [p for p in generated if is_configuration_unit(p)]
    config_name = configs[0].stem.upper() if configs else "CONFIG0"
    roots: list[Root] = []
    programs: dict[str, str] = {}
    tick_ns = 0
    csv_path = out_dir / "VARIABLES.csv"
    if csv_path.is_file():
        section = ""
        for row in csv.reader(csv_path.read_text().splitlines(), delimiter=";"):
            if not row or not row[0].strip():
                continue
            if row[0].startswith("//"):
                section = row[0][2:].strip().lower()
                continue
            if section == "programs" and len(row) >= 3:
                programs[row[1].strip().upper()] = row[2].strip().upper()
            elif section == "ticktime":
                tick_ns = int(row[0])
    units = [u for u in generated if u.suffix == ".c" and u.name != "POUS.c"]
    texts = {u: _LINE_DIRECTIVE.sub("", u.read_text()) for u in units}
    # program instances as the resource units define them: `MAIN RES0__INST0;`
    instances = {f"{domain}__{name}": (ctype, domain, name) for u in units if u not in configs
                 for ctype, domain, name in _INSTANCE.findall(texts[u]) if ctype in ctypes_.pous}
    for path, ptype in programs.items():
        parts = path.split(".")
        if len(parts) == 2:   # a CONFIGURATION without RESOURCE: iec2c's C still has one (RESOURCE__INST0)
            cname = next((c for c, (_, _, name) in instances.items() if name.upper() == parts[1]), parts[1])
        else:                 # CONFIG0.RES0.INST0 -> RES0__INST0, Beremiz's rule
            cname = "__".join(parts[1:])
        roots.append(Root(path, cname, "PROGRAM", ptype))
    for unit in units:
        is_config = unit in configs
        for how, ctype, domain, name in _GLOBAL.findall(texts[unit]):
            scope = config_name if is_config else f"{config_name}.{domain.upper()}"
            roots.append(Root(f"{scope}.{name}", f"{domain}__{name}", "GLOBAL" + how, ctype, scope, name))
    found = {r.cname for r in roots}
    for cname, (ctype, domain, name) in instances.items():   # those VARIABLES.csv does not list
        if cname not in found:
            roots.append(Root(f"{config_name}.{domain}.{name}".upper(), cname, "PROGRAM", ctype))
    located = out_dir / "LOCATED_VARIABLES.h"
    if located.is_file():
        for ctype, cname, direction, size, loc in _LOCATED.findall(located.read_text()):
            parts = [p.strip() for p in loc.split(",") if p.strip()]
            size = size if size in "XBWDL" else ""
            roots.append(Root(f"%{direction}{size}{'.'.join(parts)}", cname, "LOCATION", ctype))
    if not tick_ns:
        cfg = "".join(p.read_text() for p in configs)
        m = re.search(r"common_ticktime__\s*=\s*(\d+)ULL\s*\*\s*(\d+)ULL", cfg)
        tick_ns = int(m[1]) * int(m[2]) if m else 0
    return roots, tick_ns


# ---- the manifest -------------------------------------------------------------------------------------

class ManifestBuilder:
    """C declarations + ST declarations -> manifest types, with the C spelling of each for sizeof."""

    def __init__(self, ct: CTypes, decls: st_decls.Declarations, program_types: set[str]):
        self.ct, self.decls, self.program_types = ct, decls, program_types
        self.types: dict[str, dict] = {}
        self.cname: dict[str, str] = {}     # manifest reference -> C type for sizeof
        self.warnings: list[str] = []

    def ref(self, ctype: str, spec: st_decls.TypeSpec | None, where: str) -> str:
        """The manifest type reference of a C type, given the ST declaration it came from (if known)."""
        while ctype in self.ct.derived:
            ctype = self.ct.derived[ctype]
        if ctype in ELEMENTARY:
            self.cname.setdefault(ctype, ctype)
            return ctype
        if ctype in self.ct.enums:
            self._add(ctype, {"kind": "enum", "values": self.ct.enums[ctype]}, ctype)
            return ctype
        if ctype in self.ct.structs:
            if ctype not in self.types:
                self.types[ctype] = {}   # placeholder against recursion
                st = self.decls.types.get(ctype)
                _, st = self.decls.resolve(st)
                fields = [{"name": m, "type": self.ref(t, st.fields.get(m) if st and st.kind == "struct" else None,
                                                       f"{ctype}.{m}")} for t, m in self.ct.structs[ctype]]
                self._add(ctype, {"kind": "struct", "fields": fields}, ctype)
            return ctype
        if ctype in self.ct.arrays:
            return self._array(ctype, spec, where)
        if ctype in self.ct.pous:
            if ctype not in self.types:
                self.types[ctype] = {}
                pou = self.decls.pous.get(ctype)
                fields = []
                for how, mtype, member in self.ct.pous[ctype]:
                    mspec = pou.vars.get(member) if pou else None
                    if how == "INSTANCE":
                        r = self.ref(mtype, mspec, f"{ctype}.{member}")
                    elif how == "EXTERNAL_FB":
                        r = self.wrap("ref", self.ref(mtype, mspec, f"{ctype}.{member}"), mtype)
                    else:
                        r = self.wrap("var" if how == "VAR" else "ptr", self.ref(mtype, mspec, f"{ctype}.{member}"),
                                      mtype)
                    fields.append({"name": member, "type": r})
                kind = "program" if ctype in self.program_types or (pou and pou.kind == "PROGRAM") else "fb"
                self._add(ctype, {"kind": kind, "fields": fields}, ctype)
            return ctype
        raise MatiecError(f"{where}: C type {ctype} is not declared in the generated headers")

    def _array(self, ctype: str, spec: st_decls.TypeSpec | None, where: str) -> str:
        base, sizes = self.ct.arrays[ctype]
        name, st = self.decls.resolve(spec)
        if st is not None and st.kind == "array" and [hi - lo + 1 for lo, hi in st.dims] == sizes:
            dims = [list(d) for d in st.dims]
            elem_spec = st.elem
        else:
            dims = [[0, n - 1] for n in sizes]
            elem_spec = None
            name = ""
            self.warnings.append(f"{where}: no ST declaration found for this {ctype}; assuming lower bounds 0")
        if not name:   # anonymous ARRAY[..] OF: the C name, plus the lower bounds when they are not 0
            lows = [lo for lo, _ in dims]
            name = ctype if not any(lows) else ctype + "__FROM_" + "_".join(str(lo).replace("-", "M") for lo in lows)
        decl = {"kind": "array", "elem": self.ref(base, elem_spec, f"{where}[]"), "dims": dims}
        self._add(name, decl, ctype, where)
        return name

    def _add(self, name: str, decl: dict, ctype: str, where: str = "") -> None:
        old = self.types.get(name)
        if old and old != decl:
            raise MatiecError(f"{where or name}: type {name} is declared twice with different layouts")
        self.types[name] = decl
        self.cname[name] = ctype

    def wrap(self, prefix: str, inner: str, ctype: str) -> str:
        ref = f"{prefix}:{inner}"
        while ctype in self.ct.derived:
            ctype = self.ct.derived[ctype]
        base = self.cname.get(inner, ctype)
        self.cname[ref] = {"var": f"__IEC_{base}_t", "ptr": f"__IEC_{base}_p", "ref": f"{base} *"}[prefix]
        return ref


def read_with_local_includes(path: Path, seen: set[Path] | None = None) -> str:
    """A header with the headers it includes from its own folder inlined (POUS.h includes one header
    per POU under -O p)."""
    seen = set() if seen is None else seen
    seen.add(path)
    out = []
    for line in path.read_text().splitlines():
        m = re.match(r'^\s*#include\s+"([^"]+)"', line)
        inc = path.parent / m[1] if m else None
        if inc is not None and inc.is_file() and inc not in seen:
            out.append(read_with_local_includes(inc, seen))
        else:
            out.append(line)
    return "\n".join(out)


def describe(out_dir: Path, generated: list[Path], sources: Sources, m: Matiec,
             backend_version: str) -> tuple[dict, str, list[Root]]:
    """(manifest, plc_tables.c source, roots) for iec2c's output in out_dir; `generated` are the
    configuration and resource units."""
    ct = CTypes()
    for header in ("iec_std_FB.h",):   # the standard FBs (TON, CTU...) as the generated code sees them
        path = m.include / header
        if path.is_file():
            parse_header(path.read_text(), ct, header)
    parse_header(read_with_local_includes(out_dir / "POUS.h"), ct)
    try:
        decls = st_decls.scan_paths(sources.files, sources.root, sources.search)
    except BuiltinCompileError as exc:   # iec2c took it, but the declarations cannot be read (an IL body, say)
        diags = [*map(str, exc.diagnostics),
                 "note: the MatIEC backend reads array bounds and POU positions with the builtin parser, "
                 "which does not parse this; IL and SFC bodies are not supported"]
        raise MatiecError("\n".join(diags), diags) from None
    roots, tick_ns = parse_roots(out_dir, generated, ct)
    builder = ManifestBuilder(ct, decls, {r.ctype for r in roots if r.how == "PROGRAM"})
    mroots = []
    for r in roots:
        spec = decls.globals.get(r.scope, {}).get(r.name) if r.scope else None
        inner = builder.ref(r.ctype, spec, r.path)
        ref = {"GLOBAL": lambda: builder.wrap("var", inner, r.ctype),
               "GLOBAL_LOCATED": lambda: builder.wrap("ptr", inner, r.ctype)}.get(r.how, lambda: inner)()
        mroots.append({"path": r.path, "type": ref})
    size_checks = [ref for ref in builder.cname if not ref.startswith("ref:")]
    pous = {name: {"file": p.file, "line": p.line, "kind": p.kind} for name, p in decls.pous.items()}
    manifest = {
        "schema": 1,
        "backend": NAME,
        "backend_version": backend_version,
        "tick_ns": tick_ns,
        "types": builder.types,
        "roots": mroots,
        "size_checks": size_checks,
        "pous": pous,
    }
    if builder.warnings:
        manifest["warnings"] = builder.warnings
    return manifest, tables_c(roots, [builder.cname[s] for s in size_checks]), roots


def tables_c(roots: list[Root], size_exprs: list[str]) -> str:
    lines = ["/* Generated by linmot_st.toolchain.matiec: where each manifest root lives, and the size of",
             " * each manifest type as this compiler lays it out. */",
             '#include "iec_std_lib.h"', '#include "accessor.h"', '#include "POUS.h"', ""]
    addrs = []
    for r in roots:
        if r.how == "LOCATION":   # storage for a located variable; the generated code reads it via the pointer
            lines.append(f"static {r.ctype} plc_located_{r.cname};")
            lines.append(f"{r.ctype} *{r.cname} = &plc_located_{r.cname};")
            addrs.append(f"&plc_located_{r.cname}")
            continue
        decl = {"GLOBAL": f"__IEC_{r.ctype}_t", "GLOBAL_LOCATED": f"__IEC_{r.ctype}_p"}.get(r.how, r.ctype)
        lines.append(f"extern {decl} {r.cname};")
        addrs.append(f"&{r.cname}")
    lines += ["", "void *plc_root_addr(int i)", "{",
              f"    static void *const table[] = {{{', '.join(addrs) or '0'}}};",
              f"    return (i >= 0 && i < {len(addrs)}) ? table[i] : 0;", "}", "",
              "unsigned long plc_type_size(int i)", "{",
              f"    static const unsigned long table[] = {{{', '.join(f'sizeof({e})' for e in size_exprs) or '0'}}};",
              f"    return (i >= 0 && i < {len(size_exprs)}) ? table[i] : 0;", "}", ""]
    return "\n".join(lines)


def generate(m: Matiec, sources: Sources, out_dir: Path, backend_version: str) -> tuple[dict, list[Path], list[Path]]:
    """iec2c + tables: (manifest, C units to compile with the bounds trap, the tables unit)."""
    generated = run_iec2c(m, sources, out_dir)
    pous_h = out_dir / "POUS.h"
    text = pous_h.read_text()
    if "#endif //__POUS_H" not in text:   # iec2c writes it only when it meets a CONFIGURATION
        pous_h.write_text(text.rstrip("\n") + "\n#endif //__POUS_H\n")
    pou_files = split_pous(out_dir)
    config_units = [p for p in generated
                    if p.suffix == ".c" and p.name != "POUS.c" and p.name not in (pou_files or ())]
    manifest, tables, roots = describe(out_dir, config_units, sources, m, backend_version)
    tables_path = out_dir / "plc_tables.c"
    tables_path.write_text(tables)
    units = list(config_units)
    has_config = any(is_configuration_unit(p) for p in units)
    if pou_files is None:   # one POUS.c, included by Res0.c (or by the library unit)
        if not has_config:
            library = out_dir / "plc_library.c"
            library.write_text(LIBRARY_UNIT.format(pous='#include "POUS.c"'))
            units.append(library)
        return manifest, units, [tables_path]
    # -O p: POUS.c only includes one .c per POU. Res0.c would compile them all in one unit; instead it
    # loses that include and the POUs are compiled in balanced groups, in parallel.
    for unit in units:
        unit.write_text(re.sub(r'^\s*#include\s+"POUS\.c"\s*$', "", unit.read_text(), flags=re.M))
    units += pou_units(out_dir, pou_files, roots)
    if not has_config:
        library = out_dir / "plc_library.c"
        library.write_text(LIBRARY_UNIT.format(pous=""))
        units.append(library)
    return manifest, units, [tables_path]


def split_pous(out_dir: Path) -> list[str] | None:
    """The per-POU files POUS.c includes when iec2c ran with -O p; None when POUS.c holds the code."""
    lines = [ln.strip() for ln in (out_dir / "POUS.c").read_text().splitlines()]
    code = [ln for ln in lines if ln and not ln.startswith(("#line", "//", "/*", "*"))]
    names = [m[1] for m in (re.match(r'^#include\s+"([^"]+)"$', ln) for ln in code) if m]
    if not code or len(names) != len(code) or not all((out_dir / n).is_file() for n in names):
        return None
    return names


def pou_units(out_dir: Path, pou_files: list[str], roots: list[Root]) -> list[Path]:
    """Group the per-POU .c files into one unit per CPU, balanced by size. Each unit sees what Res0.c
    showed POUS.c: POUS.h and the accessors of the globals (declared here, defined in Config0.c/Res0.c)."""
    n = max(1, min(len(pou_files), os.cpu_count() or 1))
    groups: list[list[str]] = [[] for _ in range(n)]
    load = [0] * n
    for name in sorted(pou_files, key=lambda f: -(out_dir / f).stat().st_size):
        i = load.index(min(load))
        groups[i].append(name)
        load[i] += (out_dir / name).stat().st_size
    protos = []
    for r in roots:
        if r.how in ("GLOBAL", "GLOBAL_LOCATED"):
            protos += [f"extern {r.ctype} *__GET_GLOBAL_{r.name}(void);",
                       f"extern IEC_BYTE __IS_GLOBAL_{r.name}_FORCED(void);"]
        elif r.how == "GLOBAL_FB":
            protos.append(f"extern {r.ctype} *__GET_GLOBAL_{r.name}(void);")
    units = []
    for i, group in enumerate(groups):
        if not group:
            continue
        path = out_dir / f"plc_pous_{i}.c"
        body = "".join(f'#include "{name}"\n' for name in sorted(group, key=pou_files.index))
        path.write_text('/* Generated by linmot_st.toolchain.matiec: a share of the POUs (iec2c -O p). */\n'
                        '#include "iec_std_lib.h"\n#include "accessor.h"\n#include "POUS.h"\n'
                        + "\n".join(dict.fromkeys(protos)) + "\n" + body)
        units.append(path)
    return units


# A library has no CONFIGURATION, so iec2c writes no Config0.c/Res0.c and nothing includes POUS.c.
# Compiling it here still proves the generated C compiles; with no task, a scan runs nothing.
LIBRARY_UNIT = """/* Generated by linmot_st.toolchain.matiec for sources without a CONFIGURATION. */
#include "iec_std_lib.h"
#include "accessor.h"
#include "POUS.h"
{pous}

void config_init__(void) {{}}
void config_run__(unsigned long tick) {{ (void)tick; }}
unsigned long long common_ticktime__ = 0;
"""

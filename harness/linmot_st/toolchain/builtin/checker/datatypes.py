"""Data types: TYPE declarations and the type specifications of variables (arrays, structs, enumerations, subranges)."""

from __future__ import annotations

from .. import ast as A
from .. import stdfb
from .. import types as T
from .base import _Abort


class DataTypes:
    def declare_type(self, decl: A.TypeDecl) -> None:
        k = self.check_global_name(decl.name, decl.pos, "type")
        spec = decl.spec
        if isinstance(spec, A.NamedSpec):
            target = self.resolve_named(spec)
            if isinstance(target, T.PouType):
                self.error(spec.pos, "a type cannot be an alias of a function block")
            if T.is_elementary(target) or isinstance(target, T.Enum):
                ty: T.Type = T.Alias(k, target, decl.init)
                if decl.init is not None:
                    self.const_value(decl.init, target)
            else:
                if decl.init is not None:
                    self.error(decl.init.pos, "an initial value is allowed on an alias of an elementary type only")
                ty = target
        elif isinstance(spec, A.ArraySpec):
            ty = self.array_type(spec, k)
            if decl.init is not None:
                ty.init = decl.init              # type: ignore[attr-defined]
                self.const_value(decl.init, ty)
        elif isinstance(spec, A.StructSpec):
            ty = self.struct_type(spec, k)
            if decl.init is not None:
                self.error(decl.init.pos, "initialise the fields of a STRUCT type in its declaration")
        elif isinstance(spec, A.EnumSpec):
            ty = self.enum_type(spec, k)
            if decl.init is not None:
                ty.init = self.enum_value_of(decl.init, ty)      # type: ignore[attr-defined]
        elif isinstance(spec, A.SubrangeSpec):
            ty = self.subrange_type(spec, k)
            if decl.init is not None:
                ty.init = decl.init                # type: ignore[attr-defined]
                self.const_value(decl.init, ty)
        else:
            ty = self.resolve_spec(spec, k)
        self.types[k] = ty
        if ty not in self.type_order and not isinstance(ty, (T.Elem, T.Alias, T.Subrange)):
            self.type_order.append(ty)

    def resolve_named(self, spec: A.NamedSpec) -> T.Type:
        k = spec.name.upper()
        if k in T.ELEMENTARY:
            return T.ELEMENTARY[k]
        if k in T.ELEMENTARY_ALIASES:
            return T.ELEMENTARY_ALIASES[k]
        if k in self.types:
            return self.types[k]
        if k in self.failed_pous:
            raise _Abort     # its declaration was rejected, and reported
        if k in self.pous:
            pou = self.pous[k]
            if pou.kind == "FUNCTION_BLOCK":
                self.check_has_code(pou, spec.pos)
                return pou.ty
            self.error(spec.pos, f"'{spec.name}' is a {pou.kind}, not a type")
        if k in stdfb.names():
            return self.std_fb(k, spec.pos).ty
        if k in stdfb.NON_STANDARD:
            self.error(spec.pos, f"'{spec.name}' is a MatIEC extension block that the builtin compiler does not provide")
        if k in T.UNSUPPORTED_ELEMENTARY:
            self.error(spec.pos, f"type {k} is outside the supported subset")
        self.error(spec.pos, f"unknown type '{spec.name}' (types must be declared before they are used)")

    def resolve_spec(self, spec: A.Node, name: str | None = None) -> T.Type:
        if isinstance(spec, A.NamedSpec):
            return self.resolve_named(spec)
        if isinstance(spec, A.ArraySpec):
            return self.array_type(spec, name)
        if isinstance(spec, A.StructSpec):
            if name is None:
                self.error(spec.pos, "an anonymous STRUCT is outside the supported subset; declare a STRUCT type")
            return self.struct_type(spec, name)
        if isinstance(spec, A.EnumSpec):
            if name is None:
                self.error(spec.pos, "an anonymous enumeration is outside the supported subset; declare a type")
            return self.enum_type(spec, name)
        if isinstance(spec, A.SubrangeSpec):
            return self.subrange_type(spec, name)
        if isinstance(spec, A.StringLenSpec):
            self.error(spec.pos, f"{spec.base.upper()}[{spec.length}]: string length declarations are outside "
                                 "the supported subset (MatIEC); use STRING (126 bytes)")
        if isinstance(spec, A.UnsupportedSpec):
            self.error(spec.pos, f"{spec.what} is outside the supported subset")
        self.error(spec.pos, "unsupported type specification")

    def array_type(self, spec: A.ArraySpec, name: str | None) -> T.Array:
        if spec.star:
            self.error(spec.pos, "ARRAY[*] is outside the supported subset")
        dims = []
        for lo, hi in spec.ranges:
            for b in (lo, hi):
                if isinstance(b, A.Name):
                    self.error(b.pos, "array bounds must be integer literals (MatIEC does not accept constants)")
            if hi < lo:
                self.error(spec.pos, f"empty array range {lo}..{hi}")
            dims.append((lo, hi))
        elem = self.resolve_spec(spec.elem)
        if isinstance(elem, T.Array):
            self.error(spec.elem.pos, "an array of arrays is outside the supported subset; use a multi-dimensional array")
        if isinstance(elem, T.PouType):
            self.error(spec.elem.pos, "arrays of function block instances are outside the supported subset (MatIEC)")
        count = 1
        for lo, hi in dims:
            count *= hi - lo + 1
        if count > 1 << 24:
            self.error(spec.pos, "array too large")
        if name is None:
            self.anon += 1
            cname = f"__ARRAY{self.anon}"
            ty = T.Array(cname, elem, dims, cname, anonymous=True)
            self.type_order.append(ty)
        else:
            ty = T.Array(name, elem, dims, name)
        return ty

    def struct_type(self, spec: A.StructSpec, name: str) -> T.Struct:
        st = T.Struct(name, [], name)
        seen = set()
        for f in spec.fields:
            k = self.check_identifier(f.name, f.pos, "field")
            if k in seen:
                self.error(f.pos, f"duplicate field '{f.name}'")
            seen.add(k)
            fty = self.resolve_spec(f.spec)
            if isinstance(fty, T.PouType):
                self.error(f.spec.pos, "function block instances inside a STRUCT are outside the supported subset")
            if f.init is not None:
                self.const_value(f.init, fty)
            st.fields.append(T.Field(f.name, k, fty, f.init, f.pos))
        return st

    def enum_type(self, spec: A.EnumSpec, name: str) -> T.Enum:
        if spec.explicit:
            self.error(spec.pos, "enumerated values with explicit numbers (A := 1) are outside the supported subset (MatIEC)")
        values, spelled = [], []
        for v, pos in spec.values:
            k = self.check_identifier(v, pos, "enumerated value")
            if k in values:
                self.error(pos, f"duplicate enumerated value '{v}'")
            values.append(k)
            spelled.append(v)
        en = T.Enum(name, values, spelled)
        for v in values:
            self.enum_index.setdefault(v, []).append(en)
        return en

    def subrange_type(self, spec: A.SubrangeSpec, name: str | None) -> T.Subrange:
        base = T.ELEMENTARY.get(spec.base.upper())
        if base is None or not T.is_int(base):
            self.error(spec.pos, f"a subrange needs an integer base type, not '{spec.base}'")
        if spec.lo > spec.hi:
            self.error(spec.pos, f"empty subrange {spec.lo}..{spec.hi}")
        for b in (spec.lo, spec.hi):
            if not T.fits(b, base):
                self.error(spec.pos, f"subrange bound {b} does not fit {base.name}")
        return T.Subrange(name or f"{base.name}({spec.lo}..{spec.hi})", base, spec.lo, spec.hi)

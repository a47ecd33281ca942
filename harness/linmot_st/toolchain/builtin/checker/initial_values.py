"""Initial values: constants, array and STRUCT initialisers, enumerated values, checked against their type."""

from __future__ import annotations

from .. import ast as A
from .. import types as T


def _date_field(t: T.Type, path: str = "") -> tuple[str, T.Type] | None:
    """The first DATE or DT inside a type (through fields and array elements), with its path."""
    tb = t.base()
    if tb is T.DATE or tb is T.DT:
        return path, tb
    if isinstance(tb, T.Struct):
        for f in tb.fields:
            found = _date_field(f.ty, f"{path}.{f.name}" if path else f.name)
            if found:
                return found
    if isinstance(tb, T.Array):
        return _date_field(tb.elem, path + "[]")
    return None


def _bulk_fits(values: list[int], ty: T.Type) -> bool:
    """A long list of plain integer literals (bulkinit) that initialises an array of an integer or bit
    string type, every value in range and no more values than elements: what the item-by-item checks
    would accept."""
    if not isinstance(ty, T.Array) or len(values) > ty.count:
        return False
    elem = ty.elem.base()
    if not (isinstance(elem, T.Elem) and elem.kind in ("sint", "uint", "bit")) or isinstance(ty.elem, T.Subrange):
        return False
    return T.fits(min(values), elem) and T.fits(max(values), elem)


class InitialValues:
    def const_value(self, init: A.Node, ty: T.Type) -> None:
        """Check an initial value against its type (the value itself is computed by codegen)."""
        tb = ty.base() if not isinstance(ty, T.Subrange) else ty
        if isinstance(init, A.ArrayInit) and init.ints is not None:
            if _bulk_fits(init.ints.values, ty):
                return
            init.items, init.ints = init.entries(), None    # the ordinary checks and messages
        if isinstance(init, A.ArrayInit):
            if not isinstance(ty, T.Array):
                self.error(init.pos, f"an array initialiser for a variable of type {T.describe(ty)}")
            if isinstance(ty.elem.base(), T.Enum):
                self.error(init.pos, "initial values for an array of enumerated values are outside the supported "
                                     "subset (iec2c stops with an internal error)")
            total = 0
            for count, value in init.items:
                if count < 1:
                    self.error(init.pos, "a repetition count must be at least 1")
                total += count
                if isinstance(value, A.StructInit) and isinstance(ty.elem.base(), T.Struct):
                    self.error(value.pos, "STRUCT initialisers as elements of an array initialiser are outside the "
                                          "supported subset (MatIEC rejects them); assign the elements in the body")
                if value is not None:
                    self.const_value(value, ty.elem)
            if total > ty.count:
                self.error(init.pos, f"too many initial values: {total} for {ty.count} elements")
            return
        if isinstance(init, A.StructInit):
            if not isinstance(ty, (T.Struct, T.PouType)):
                self.error(init.pos, f"a structure initialiser for a variable of type {T.describe(ty)}")
            if isinstance(ty, T.Struct):
                dated = _date_field(ty)
                if dated is not None:
                    self.error(init.pos, f"{ty.name} holds a {dated[1].name} ('{dated[0]}'): a STRUCT initialiser of "
                                         "a type with a DATE or DT inside is outside the supported subset (MatIEC's "
                                         "C initialises those with a function call where C needs a constant); give "
                                         "the fields defaults in the STRUCT type, or assign them in the body")
            seen = set()
            for fname, pos, value in init.items:
                k = fname.upper()
                if k in seen:
                    self.error(pos, f"field '{fname}' initialised twice")
                seen.add(k)
                if isinstance(ty, T.Struct):
                    self.struct_field_init(ty, fname, pos, value)
                else:
                    v = ty.pou.vars.get(k)
                    if v is None or v.kind not in ("VAR_INPUT", "VAR_OUTPUT", "VAR") or v.implicit:
                        self.error(pos, f"'{ty.name}' has no variable '{fname}' that can be initialised")
                    self.const_value(value, v.ty)
            return
        if isinstance(ty, (T.Array, T.Struct)):
            self.error(init.pos, f"a variable of type {T.describe(ty)} needs an array or structure initialiser")
        if isinstance(ty, T.PouType):
            self.error(init.pos, "a function block instance is initialised with (name := value, ...)")
        if not isinstance(init, (A.Literal, A.EnumLit, A.Name)):
            self.error(init.pos, "an initial value must be a literal (MatIEC accepts no constant expressions here)")
        if isinstance(init, A.Name):
            if isinstance(tb.base(), T.Enum):
                self.enum_value_of(init, tb.base())
                return
            self.error(init.pos, f"'{init.name}' is not a constant this compiler can use as an initial value")
        saved, self.cur = self.cur, None
        try:
            self.coerce(init, ty, "initial value")
        finally:
            self.cur = saved

    def struct_field_init(self, st: T.Struct, fname: str, pos: A.Pos, value: A.Node) -> None:
        """One `field := value` of a STRUCT initialiser, within what MatIEC checks and compiles right.

        MatIEC (HEAD 2024-10) finds the field an initialiser names as the first field, in declaration
        order, whose upper-case name sorts at or after the given one (its list lookup uses the `<` of its
        name map as if it were `==`), and checks the value against that field's type; its C then
        initialises the right field. So an initialiser is accepted here only where that lookup finds the
        field itself, which is always the case when the fields are declared in alphabetical order."""
        k = fname.upper()
        f = st.field(k)
        if f is None:
            self.error(pos, f"'{T.describe(st)}' has no field '{fname}'")
        found = next((g for g in st.fields if g.key >= k), None)
        if found is not f:
            self.error(pos, f"field '{fname}' of {st.name} cannot be initialised here: MatIEC looks it up as the "
                            f"first field, in declaration order, whose name sorts at or after '{f.key}', which is "
                            f"'{found.name}', and checks the value against that field's type; declare the fields "
                            f"in alphabetical order, or give '{fname}' a default in the STRUCT type, or assign it in "
                            "the body")
        fb = f.ty.base()
        if isinstance(fb, T.Array):
            self.error(pos, f"field '{fname}' is an ARRAY ({T.describe(f.ty)}): array values in a STRUCT initialiser "
                            "are outside the supported subset (MatIEC rejects them); give the field a default in "
                            "the STRUCT type or assign it in the body")
        if isinstance(fb, T.Enum):
            self.error(pos, f"field '{fname}' is an enumeration ({T.describe(f.ty)}): enumerated values in a STRUCT "
                            "initialiser are outside the supported subset (iec2c crashes on them); give the field "
                            "a default in the STRUCT type or assign it in the body")
        self.const_value(value, f.ty)

    def enum_value_of(self, e: A.Node, en: T.Enum) -> int:
        if isinstance(e, A.EnumLit):
            if e.type_name != en.name:
                self.error(e.pos, f"'{e.type_name}#{e.value}' is not a value of {en.name}")
            k = e.value.upper()
        elif isinstance(e, A.Name):
            k = e.name.upper()
        else:
            self.error(e.pos, f"expected a value of {en.name}")
        if k not in en.values:
            self.error(e.pos, f"'{k}' is not a value of {en.name}")
        e.ty = en
        return en.values.index(k)

"""Parse one Structured Text file into the syntax tree of `ast.py` (lark, LALR(1), positions kept).

The AST is built while parsing (lark's inline transformer), which is about twice as fast as building a
parse tree first. Literals are decoded here: integers, reals, durations (to ns), dates (to s since
1970-01-01), times of day (to ns since midnight) and strings (the `$` escapes).
"""

from __future__ import annotations

import datetime
import functools
import re
from pathlib import Path

import lark
from lark import Token

from . import ast as A
from . import bulkinit
from .errors import BuiltinCompileError, Diagnostic

# MatIEC's C pragma {{ ... }}: iec2c pastes its text into the C it writes, unchecked
C_PRAGMA = ("C pragmas ({{ ... }}) are not supported by the builtin compiler: iec2c pastes their text into its "
            "own C, which refers to MatIEC's generated names; the builtin compiler writes different C, in which "
            "that text cannot work")


def is_c_pragma(text: str) -> bool:
    return text.startswith("{{") and text.endswith("}}")


GRAMMAR = Path(__file__).with_name("st.lark")
IMPLICIT_RESOURCE = "RESOURCE"    # the name of the resource of a CONFIGURATION written without one

# words that MatIEC does not know, or knows only outside this subset: a syntax error at one of them
# gets a message that says so rather than "unexpected token"
UNSUPPORTED_WORDS = {
    "METHOD": "METHOD (object-oriented extension)",
    "INTERFACE": "INTERFACE (object-oriented extension)",
    "EXTENDS": "EXTENDS (object-oriented extension)",
    "IMPLEMENTS": "IMPLEMENTS (object-oriented extension)",
    "PROPERTY": "PROPERTY (object-oriented extension)",
    "THIS": "THIS (object-oriented extension)",
    "SUPER": "SUPER (object-oriented extension)",
    "ABSTRACT": "ABSTRACT (object-oriented extension)",
    "FINAL": "FINAL (object-oriented extension)",
    "PUBLIC": "access specifiers (object-oriented extension)",
    "PRIVATE": "access specifiers (object-oriented extension)",
    "PROTECTED": "access specifiers (object-oriented extension)",
    "INTERNAL": "access specifiers (object-oriented extension)",
    "NAMESPACE": "NAMESPACE",
    "USING": "USING",
    "REFERENCE": "REFERENCE TO",
    "UNION": "UNION",
    "JMP": "IL",
    "ACTION": "SFC actions",
    "STEP": "SFC steps",
    "TRANSITION": "SFC transitions",
    "INITIAL_STEP": "SFC steps",
}


class _Builder(lark.Transformer):
    """lark callbacks -> AST nodes, called while parsing. `file` is set before each parse.

    lark's inline callbacks get no rule positions, so each node takes the position of a token or node
    among its children (keywords that start a statement are named terminals for that reason).
    """

    file = "<input>"
    bulk: dict = {}         # placeholder position -> bulkinit.BulkInts, for the parse under way

    def _tpos(self, tok: Token) -> A.Pos:
        return A.Pos(self.file, tok.line, tok.column)

    def _err(self, pos: A.Pos, msg: str):
        raise BuiltinCompileError([Diagnostic(pos.file, pos.line, pos.col, msg)])

    # ------------------------------------------------------------ top level
    def start(self, items):
        return list(items)

    def top_pragma(self, items):
        return A.Pragma(self._tpos(items[0]), str(items[0]))

    def type_block(self, items):
        return A.TypeBlock(items[0].pos, list(items))

    def type_decl(self, items):
        name, spec, init = items
        return A.TypeDecl(self._tpos(name), str(name), spec, init)

    def named_type(self, items):
        return A.NamedSpec(self._tpos(items[0]), str(items[0]))

    def array_spec(self, items):
        kw, *ranges, elem = items
        return A.ArraySpec(self._tpos(kw), ranges, elem)

    def array_star(self, items):
        return A.ArraySpec(self._tpos(items[0]), [], items[-1], star=True)

    def array_range(self, items):
        return (items[0], items[1])

    def const_name(self, items):
        return A.Name(self._tpos(items[0]), str(items[0]))

    def signed_int(self, items):
        return _int_value(items[0])

    def neg_int(self, items):
        return -_int_value(items[0])

    def struct_spec(self, items):
        kw, *fields = items
        return A.StructSpec(self._tpos(kw), fields)

    def struct_field(self, items):
        name, spec, init = items
        return A.StructField(self._tpos(name), str(name), spec, init)

    def enum_spec(self, items):
        explicit = any(v is not None for _, _, v in items)
        return A.EnumSpec(items[0][1], [(n, p) for n, p, _ in items], explicit)

    def enum_item(self, items):
        return (str(items[0]), self._tpos(items[0]), items[1])

    def subrange_spec(self, items):
        base, lo, hi = items
        return A.SubrangeSpec(self._tpos(base), str(base), lo, hi)

    def string_len_spec(self, items):
        return A.StringLenSpec(self._tpos(items[0]), str(items[0]), _int_value(items[1]))

    def pointer_spec(self, items):
        return A.UnsupportedSpec(self._tpos(items[0]), f"{str(items[0]).upper()} TO")

    def ref_spec(self, items):
        return A.UnsupportedSpec(self._tpos(items[0]), "REF_TO")

    def array_init(self, items):
        out = [it if isinstance(it, tuple) else (1, it) for it in items]
        first = out[0][1]
        if len(out) == 1 and isinstance(first, A.Literal) and first.text == "0" and self.bulk:
            bulk = self.bulk.pop((first.pos.line, first.pos.col), None)
            if bulk is not None:      # the placeholder of a long literal list (bulkinit)
                line, col = bulk.first_pos()
                return A.ArrayInit(A.Pos(self.file, line, col), [], bulk)
        return A.ArrayInit(first.pos if first is not None else A.Pos(self.file, 0, 0), out)

    def array_repeat(self, items):
        count, value = items
        return (_int_value(count), value)

    def struct_init(self, items):
        return A.StructInit(items[0][1], list(items))

    def struct_init_item(self, items):
        name, value = items
        return (str(name), self._tpos(name), value)

    # ------------------------------------------------------------ variables
    def var_block(self, items):
        kind, qual, *decls = items
        return A.VarBlock(self._tpos(kind), str(kind).upper(), str(qual).upper() if qual else None, decls)

    def var_decl(self, items):
        names, spec, init = items
        return A.VarDecl(names[0][1], names, spec, init)

    def located_decl(self, items):
        name, loc, spec, init = items
        return A.VarDecl(self._tpos(name), [(str(name), self._tpos(name))], spec, init, location=str(loc).upper())

    def anon_located_decl(self, items):
        loc, spec, init = items
        return A.VarDecl(self._tpos(loc), [], spec, init, location=str(loc).upper())

    def edge_decl(self, items):
        names, spec, edge = items
        return A.VarDecl(names[0][1], names, spec, None, edge=str(edge).upper())

    def ident_list(self, items):
        return [(str(t), self._tpos(t)) for t in items]

    # ------------------------------------------------------------ POUs
    def function(self, items):
        name, ret, *blocks, body = items
        return A.Pou(self._tpos(name), "FUNCTION", str(name), ret, blocks, body)

    def function_block(self, items):
        name, *blocks, body = items
        return A.Pou(self._tpos(name), "FUNCTION_BLOCK", str(name), None, blocks, body)

    def program(self, items):
        name, *blocks, body = items
        return A.Pou(self._tpos(name), "PROGRAM", str(name), None, blocks, body)

    def body(self, items):
        return list(items)

    # ------------------------------------------------------------ configuration
    def configuration(self, items):
        name, *rest = items
        blocks = [x for x in rest if isinstance(x, A.VarBlock)]
        resources = [x for x in rest if isinstance(x, A.Resource)]
        return A.Configuration(self._tpos(name), str(name), blocks, resources)

    def resource(self, items):
        name, on, *rest = items
        return A.Resource(self._tpos(name), str(name), str(on),
                          [x for x in rest if isinstance(x, A.VarBlock)],
                          [x for x in rest if isinstance(x, A.TaskDecl)],
                          [x for x in rest if isinstance(x, A.ProgramConfig)])

    def single_resource(self, items):
        # MatIEC names this resource RESOURCE in its C (RESOURCE__INST) and leaves it out of the
        # variables' paths (CONFIG.INST.VAR)
        return A.Resource(items[0].pos, IMPLICIT_RESOURCE, "", [],
                          [x for x in items if isinstance(x, A.TaskDecl)],
                          [x for x in items if isinstance(x, A.ProgramConfig)], implicit=True)

    def task(self, items):
        name, *params = items
        return A.TaskDecl(self._tpos(name), str(name), params)

    def task_param(self, items):
        name, value = items
        return (str(name), self._tpos(name), value)

    def program_config(self, items):
        name, task, type_name, *bindings = items
        bindings = [b for b in bindings if b is not None]
        return A.ProgramConfig(self._tpos(name), str(name), str(task) if task else None, str(type_name),
                               self._tpos(type_name), bindings)

    def prog_binding(self, items):
        name, value = items
        return (str(name), self._tpos(name), ":=", value)

    # ------------------------------------------------------------ statements
    def assignment(self, items):
        target, value = items
        return A.Assign(target.pos, target, value)

    def call_statement(self, items):
        name, args = items
        call = A.Call(self._tpos(name), str(name), args or [])
        return A.CallStmt(call.pos, call)

    def if_statement(self, items):
        kw, cond, *rest = items
        body, branches, else_body = [], [], None
        i = 0
        while i < len(rest) and rest[i] is not None and not isinstance(rest[i], (tuple, _Else)):
            body.append(rest[i])
            i += 1
        branches.append((cond, body))
        for it in rest[i:]:
            if isinstance(it, tuple):
                branches.append(it)
            elif isinstance(it, _Else):
                else_body = it.body
        return A.If(self._tpos(kw), branches, else_body)

    def elsif_clause(self, items):
        cond, *body = items
        return (cond, list(body))

    def else_clause(self, items):
        return _Else(list(items))

    def case_statement(self, items):
        kw, selector, *parts = items
        else_body = None
        if parts and (parts[-1] is None or isinstance(parts[-1], _Else)):
            last = parts.pop()
            else_body = last.body if last is not None else None
        elements: list = []
        for part in parts:
            if isinstance(part, _Labels):
                elements.append((part.labels, []))
            else:
                if not elements:
                    self._err(part.pos, "syntax error: a CASE element must start with a label")
                elements[-1][1].append(part)
        return A.Case(self._tpos(kw), selector, elements, else_body)

    def case_stmt(self, items):
        return items[0]

    def case_labels(self, items):
        return _Labels(list(items), items[0].pos)

    def case_label(self, items):
        return A.CaseLabel(items[0].pos, items[0], None)

    def case_range(self, items):
        return A.CaseLabel(items[0].pos, items[0], items[1])

    # values of CASE labels reuse the expression nodes
    def case_int(self, items):
        tok = items[0]
        return A.Literal(self._tpos(tok), "int", _int_value(tok), None, str(tok))

    def case_neg_int(self, items):
        tok = items[0]
        return A.Literal(self._tpos(tok), "int", -_int_value(tok), None, "-" + str(tok))

    def case_name(self, items):
        return A.Name(self._tpos(items[0]), str(items[0]))

    def case_typed_name(self, items):
        prefix, name = items
        return A.EnumLit(self._tpos(prefix), str(prefix)[:-1].upper(), str(name))

    def case_typed_int(self, items):
        prefix, value = items
        return A.Literal(self._tpos(prefix), "int", value, str(prefix)[:-1].upper(), str(value))

    def for_statement(self, items):
        kw, var, start, end, step, *body = items
        name = A.Name(self._tpos(var), str(var))
        return A.For(self._tpos(kw), name, start, end, step, list(body))

    def while_statement(self, items):
        kw, cond, *body = items
        return A.While(self._tpos(kw), cond, list(body))

    def repeat_statement(self, items):
        kw, *body, cond = items
        return A.Repeat(self._tpos(kw), list(body), cond)

    def exit_statement(self, items):
        return A.Exit(self._tpos(items[0]))

    def continue_statement(self, items):
        return A.Continue(self._tpos(items[0]))

    def return_statement(self, items):
        return A.Return(self._tpos(items[0]))

    def pragma_statement(self, items):
        return A.PragmaStmt(self._tpos(items[0]), str(items[0]))

    # ------------------------------------------------------------ expressions
    def _bin(op):  # noqa: N805 - a factory of callbacks
        def cb(self, items):
            left, right = items
            return A.BinOp(left.pos, op, left, right)
        return cb

    or_op = _bin("OR")
    xor_op = _bin("XOR")
    and_op = _bin("AND")
    eq_op = _bin("=")
    ne_op = _bin("<>")
    lt_op = _bin("<")
    gt_op = _bin(">")
    le_op = _bin("<=")
    ge_op = _bin(">=")
    add_op = _bin("+")
    sub_op = _bin("-")
    mul_op = _bin("*")
    div_op = _bin("/")
    mod_op = _bin("MOD")
    power = _bin("**")

    def neg(self, items):
        operand = items[0]
        pos = A.Pos(operand.pos.file, operand.pos.line, max(1, operand.pos.col - 1))
        # `-5` is a signed literal (its range is checked as a whole), `-(5)` is a negation
        if isinstance(operand, A.Literal) and operand.kind in ("int", "real") and not operand.paren \
                and operand.type_name is None:
            operand.value = -operand.value
            operand.text = "-" + operand.text
            return operand
        return A.UnOp(pos, "NEG", operand)

    def not_op(self, items):
        return A.UnOp(items[0].pos, "NOT", items[0])

    def paren(self, items):
        e = items[0]
        e.paren += 1
        return e

    def direct_var(self, items):
        return A.DirectVar(self._tpos(items[0]), str(items[0]).upper())

    def function_call(self, items):
        name, args = items
        return A.Call(self._tpos(name), str(name), args or [])

    def arguments(self, items):
        return list(items)

    def positional_arg(self, items):
        return A.Arg(items[0].pos, None, items[0])

    def input_arg(self, items):
        name, value = items
        return A.Arg(self._tpos(name), str(name), value)

    def output_arg(self, items):
        name, var = items
        return A.Arg(self._tpos(name), str(name), var, output=True)

    def neg_output_arg(self, items):
        name, var = items
        return A.Arg(self._tpos(name), str(name), var, output=True, negated=True)

    def variable(self, items):
        head, *sels = items
        node: A.Node = A.Name(self._tpos(head), str(head))
        for kind, pos, payload in sels:
            if kind == "field":
                node = A.Member(node.pos, node, payload, pos)
            elif kind == "index":
                node = A.Index(node.pos, node, payload)
            elif kind == "bit":
                node = A.BitAccess(pos, node, payload)
            else:
                node = A.Deref(pos, node)
        return node

    def field_sel(self, items):
        return ("field", self._tpos(items[0]), str(items[0]))

    def bit_sel(self, items):
        return ("bit", self._tpos(items[0]), str(items[0]))

    def index_sel(self, items):
        return ("index", items[0].pos, list(items))

    def deref_sel(self, items):
        return ("deref", self._tpos(items[0]), None)

    # ------------------------------------------------------------ literals
    def int_lit(self, items):
        tok = items[0]
        return A.Literal(self._tpos(tok), "int", _int_value(tok), None, str(tok))

    def real_lit(self, items):
        tok = items[0]
        text = str(tok).replace("_", "")
        return A.Literal(self._tpos(tok), "real", float(text), None, text)

    def string_lit(self, items):
        tok = items[0]
        return A.Literal(self._tpos(tok), "string", _decode_string(tok, self._tpos(tok)), None, str(tok))

    def wstring_lit(self, items):
        tok = items[0]
        return A.Literal(self._tpos(tok), "wstring", b"", None, str(tok))

    def true_lit(self, items):
        return A.Literal(self._tpos(items[0]), "bool", True, None, "TRUE")

    def false_lit(self, items):
        return A.Literal(self._tpos(items[0]), "bool", False, None, "FALSE")

    def time_lit(self, items):
        tok = items[0]
        pos = self._tpos(tok)
        return A.Literal(pos, "time", _duration_ns(str(tok), pos), None, str(tok))

    def date_lit(self, items):
        tok = items[0]
        pos = self._tpos(tok)
        return A.Literal(pos, "date", _date_s(str(tok).split("#", 1)[1], pos) * 10**9, None, str(tok))

    def tod_lit(self, items):
        tok = items[0]
        pos = self._tpos(tok)
        return A.Literal(pos, "tod", _tod_ns(str(tok).split("#", 1)[1], pos), None, str(tok))

    def dt_lit(self, items):
        tok = items[0]
        pos = self._tpos(tok)
        body = str(tok).split("#", 1)[1]
        y, mo, d, rest = body.split("-", 3)
        return A.Literal(pos, "dt", _date_s(f"{y}-{mo}-{d}", pos) * 10**9 + _tod_ns(rest, pos), None, str(tok))

    def typed_lit(self, items):
        prefix, (kind, value, text) = items
        pos = self._tpos(prefix)
        tname = str(prefix)[:-1].upper()
        if kind == "name":
            return A.EnumLit(pos, tname, value)
        return A.Literal(pos, kind, value, tname, text)

    def tv_int(self, items):
        return ("int", _int_value(items[0]), str(items[0]))

    def tv_neg_int(self, items):
        return ("int", -_int_value(items[0]), "-" + str(items[0]))

    def tv_real(self, items):
        t = str(items[0]).replace("_", "")
        return ("real", float(t), t)

    def tv_neg_real(self, items):
        t = str(items[0]).replace("_", "")
        return ("real", -float(t), "-" + t)

    def tv_true(self, items):
        return ("bool", True, "TRUE")

    def tv_false(self, items):
        return ("bool", False, "FALSE")

    def tv_name(self, items):
        return ("name", str(items[0]), str(items[0]))

    def tv_string(self, items):
        return ("string", _decode_string(items[0], self._tpos(items[0])), str(items[0]))


class _Else:
    def __init__(self, body):
        self.body = body


class _Labels:
    def __init__(self, labels, pos):
        self.labels = labels
        self.pos = pos


# ------------------------------------------------------------------ literal decoding

def _int_value(tok) -> int:
    text = str(tok).replace("_", "")
    if "#" in text:
        base, digits = text.split("#", 1)
        try:
            return int(digits, int(base))
        except ValueError:
            line, col = getattr(tok, "line", 0) or 0, getattr(tok, "column", 0) or 0
            raise BuiltinCompileError([Diagnostic(_Builder.file, line, col,
                                                  f"invalid base-{base} literal {str(tok)!r}")]) from None
    return int(text)


_STRING_ESCAPES = {"$": b"$", "'": b"'", '"': b'"', "L": b"\n", "N": b"\n", "P": b"\f", "R": b"\r", "T": b"\t"}


def _decode_string(tok, pos: A.Pos) -> bytes:
    body = str(tok)[1:-1]
    out = bytearray()
    i = 0
    while i < len(body):
        c = body[i]
        if c != "$":
            out += c.encode("latin-1", errors="strict") if ord(c) < 256 else b"?"
            i += 1
            continue
        nxt = body[i + 1:i + 2]
        if nxt.upper() in _STRING_ESCAPES:
            out += _STRING_ESCAPES[nxt.upper()]
            i += 2
        elif re.fullmatch(r"[0-9A-Fa-f]{2}", body[i + 1:i + 3] or ""):
            out.append(int(body[i + 1:i + 3], 16))
            i += 3
        else:
            raise BuiltinCompileError([Diagnostic(pos.file, pos.line, pos.col + i + 1,
                                                  f"invalid escape '${nxt}' in string literal")])
    return bytes(out)


_UNIT_NS = {"d": 86400 * 10**9, "h": 3600 * 10**9, "m": 60 * 10**9, "s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}


def _duration_ns(text: str, pos: A.Pos) -> int:
    body = text.split("#", 1)[1].replace("_", "").lower()
    sign = 1
    if body[:1] in "+-":
        sign = -1 if body[0] == "-" else 1
        body = body[1:]
    total = 0
    last_rank = -1
    order = ["d", "h", "m", "s", "ms", "us", "ns"]
    for num, unit in re.findall(r"([0-9.]+)(ms|us|ns|d|h|m|s)", body):
        rank = order.index(unit)
        if rank <= last_rank or num.count(".") > 1:
            raise BuiltinCompileError([Diagnostic(pos.file, pos.line, pos.col, f"invalid duration literal {text!r}")])
        last_rank = rank
        if "." in num:
            # exact decimal arithmetic: T#1.5s is 1_500_000_000 ns
            whole, frac = num.split(".")
            total += int(whole or "0") * _UNIT_NS[unit] + int(frac or "0") * _UNIT_NS[unit] // 10 ** len(frac)
        else:
            total += int(num) * _UNIT_NS[unit]
    return sign * total


def _date_s(text: str, pos: A.Pos) -> int:
    try:
        y, m, d = (int(x) for x in text.split("-"))
        return (datetime.date(y, m, d) - datetime.date(1970, 1, 1)).days * 86400
    except ValueError:
        raise BuiltinCompileError([Diagnostic(pos.file, pos.line, pos.col, f"invalid date {text!r}")]) from None


def _tod_ns(text: str, pos: A.Pos) -> int:
    parts = text.split(":")
    try:
        h, m = int(parts[0]), int(parts[1])
        sec = parts[2] if len(parts) > 2 else "0"
        whole, _, frac = sec.partition(".")
        s = int(whole)
        if not (0 <= h < 24 and 0 <= m < 60 and 0 <= s < 60):
            raise ValueError
        return ((h * 60 + m) * 60 + s) * 10**9 + (int(frac) * 10**9 // 10 ** len(frac) if frac else 0)
    except (ValueError, IndexError):
        raise BuiltinCompileError([Diagnostic(pos.file, pos.line, pos.col, f"invalid time of day {text!r}")]) from None


# ------------------------------------------------------------------ the parser

@functools.lru_cache(maxsize=1)
def _parser() -> tuple[lark.Lark, _Builder]:
    builder = _Builder()
    parser = lark.Lark(GRAMMAR.read_text(), parser="lalr", lexer="contextual",
                       maybe_placeholders=True, transformer=builder, cache=True)
    return parser, builder


def tokens(text: str) -> list[lark.Token]:
    """The lexer's tokens of `text` with comments kept and white space dropped: what tools that rewrite
    ST without changing it (the exporter) need to find comments and exact source spans."""
    return [t for t in _parser()[0].lex(text, dont_ignore=True) if t.type != "WS"]


def parse(text: str, file: str) -> list[A.Node]:
    """Parse one file's text; `file` is the name diagnostics use. Raises BuiltinCompileError."""
    parser, builder = _parser()
    builder.file = file
    fast_text, builder.bulk = bulkinit.extract(text)
    try:
        if builder.bulk:
            nodes = parser.parse(fast_text)
            if not builder.bulk:
                return nodes
            # a placeholder the grammar never reached (inside a comment or a string): read it all as written
            builder.bulk = {}
        return parser.parse(text)
    except lark.exceptions.VisitError as exc:       # an error raised inside a callback
        if isinstance(exc.orig_exc, BuiltinCompileError):
            raise _named(exc.orig_exc, file) from None
        raise
    except BuiltinCompileError as exc:
        raise _named(exc, file) from None
    except lark.UnexpectedInput as exc:
        raise BuiltinCompileError([_syntax_diagnostic(exc, text, file)]) from None


def _named(exc: BuiltinCompileError, file: str) -> BuiltinCompileError:
    """Diagnostics raised by literal decoding, which does not know the file name, get it here."""
    return BuiltinCompileError([Diagnostic(file, d.line, d.col, d.message) if d.file == _Builder.file else d
                                for d in exc.diagnostics])


def _syntax_diagnostic(exc: lark.UnexpectedInput, text: str, file: str) -> Diagnostic:
    line = getattr(exc, "line", 0) or 0
    col = getattr(exc, "column", 0) or 0
    if isinstance(exc, lark.UnexpectedEOF) or line <= 0:
        lines = text.splitlines() or [""]
        line, col = len(lines), len(lines[-1]) + 1
        return Diagnostic(file, line, col, "syntax error: unexpected end of file")
    offset = _offset(text, line, col)
    rest = text[offset:]
    # an unterminated (* comment swallows nothing and leaves "(" "*": say what it is
    unterminated = _unterminated_comment(text)
    if unterminated is not None:
        return Diagnostic(file, unterminated[0], unterminated[1], "unterminated comment: '(*' has no matching '*)'")
    if rest.startswith("//"):
        return Diagnostic(file, line, col, "'//' comments are outside the supported subset; use (* ... *)")
    if isinstance(exc, lark.UnexpectedToken):
        tok = exc.token
        word = str(tok).upper()
        # an unsupported word that the lexer took for an identifier makes the *next* token unexpected
        before = re.search(r"([A-Za-z_]\w*)\s*$", text[:offset])
        if before and before.group(1).upper() in UNSUPPORTED_WORDS and word not in UNSUPPORTED_WORDS:
            bl = text.count("\n", 0, before.start(1)) + 1
            bc = before.start(1) - (text.rfind("\n", 0, before.start(1)) + 1) + 1
            return Diagnostic(file, bl, bc, f"{UNSUPPORTED_WORDS[before.group(1).upper()]} is outside the supported subset")
        if word in UNSUPPORTED_WORDS:
            return Diagnostic(file, line, col, f"{UNSUPPORTED_WORDS[word]} is outside the supported subset")
        if tok.type == "PRAGMA" and is_c_pragma(str(tok)):
            return Diagnostic(file, line, col, C_PRAGMA)
        if tok.type == "PRAGMA":
            return Diagnostic(file, line, col, "a pragma is not allowed here")
        if tok.type == "$END":
            return Diagnostic(file, line, col, "syntax error: unexpected end of file")
        expected = exc.expected or set()
        if "IDENT" in expected and tok.type not in ("IDENT",) and re.fullmatch(r"[A-Za-z_]\w*", str(tok)):
            return Diagnostic(file, line, col, f"syntax error: '{tok}' is a reserved word and cannot be used here")
        if str(tok) == ";" and "SEMICOLON" not in expected:
            return Diagnostic(file, line, col, "syntax error: unexpected ';' (empty statements are not allowed)")
        return Diagnostic(file, line, col, f"syntax error: unexpected '{tok}'")
    if isinstance(exc, lark.UnexpectedCharacters):
        ch = rest[:1]
        if ch == '"':
            return Diagnostic(file, line, col, "WSTRING literals are outside the supported subset")
        if ch == "#":
            return Diagnostic(file, line, col, "syntax error: invalid typed or based literal")
        return Diagnostic(file, line, col, f"syntax error: unexpected character {ch!r}")
    return Diagnostic(file, line, col, "syntax error")


def _offset(text: str, line: int, col: int) -> int:
    pos = 0
    for _ in range(line - 1):
        nl = text.find("\n", pos)
        if nl < 0:
            return len(text)
        pos = nl + 1
    return pos + col - 1


def _unterminated_comment(text: str) -> tuple[int, int] | None:
    i = 0
    in_string = None
    while i < len(text):
        c = text[i]
        if in_string:
            if c == "$":
                i += 2
                continue
            if c == in_string:
                in_string = None
        elif c in "'\"":
            in_string = c
        elif text.startswith("(*", i):
            end = text.find("*)", i + 2)
            if end < 0:
                line = text.count("\n", 0, i) + 1
                col = i - (text.rfind("\n", 0, i) + 1) + 1
                return line, col
            i = end + 2
            continue
        elif c == "{":
            end = text.find("}", i)
            if end < 0:
                return None
            i = end + 1
            continue
        i += 1
    return None

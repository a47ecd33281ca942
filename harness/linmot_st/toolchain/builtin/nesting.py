"""How deeply statements and expressions may nest: MatIEC's parser stack, modelled.

iec2c parses with a bison parser whose stack cannot grow (its location type is not trivially copyable,
so the initial depth YYINITDEPTH = 200 is also the maximum). A statement whose parse keeps more symbols
pending than that fails with "Parsing failed because of too many consecutive syntax errors", so
MatIEC accepts at most 189 nested parentheses, 94 nested calls `ABS(ABS(...))`, 63 nested IFs, 23
nested ELSIF branches, 27 nested FORs... but a sum of any number of terms, since a left-associative
chain is reduced as it is read.

The builtin compiler rejects what would overflow that stack, so that a program it accepts also parses
with MatIEC; as a bonus, it bounds the recursion of the checker and of the code generator (whose only
unbounded walk, along left-associative operator chains, is iterative).

The model: the number of symbols pending on MatIEC's stack at each point of a POU body is the sum,
over the enclosing constructs, of what each keeps pending while one of its parts is parsed (an IF
keeps `IF expr THEN` = 3 while its first statement is parsed, a call `F(` keeps 2 while its first
argument is parsed, a binary operator keeps its left operand and itself = 2 while its right operand is
parsed...), plus what the innermost token needs. Every figure below was measured with iec2c (MatIEC
HEAD of 2024-10, flags -f -l -p) by bisection on the nesting depth of each construct; where variants
differ, the largest is used, so the model may refuse a few levels that MatIEC would still accept, never
the reverse. tests/toolchain/builtin/test_builtin_nesting.py checks it against iec2c at the measured limits.
"""

from __future__ import annotations

from . import ast as A

# bison's stack of 200 entries, in the units of the measurements below (`i := ` followed by 189
# parentheses and `i` is the deepest assignment MatIEC accepts at the top of a PROGRAM body)
LIMIT = 200
# pending at the first statement of a body: the library, the POU header and its VAR blocks
BODY_BASE = {"PROGRAM": 8, "FUNCTION_BLOCK": 8, "FUNCTION": 9}
LATER_STATEMENT = 1        # the statement list before the second and later statements of a list

# the innermost token: most need 1; a few literals are several tokens to MatIEC's lexer
_LITERAL_COST = {"time": 8, "date": 6, "tod": 6, "dt": 8}
TYPED_LITERAL = 3          # INT#-5
ENUM_LITERAL = 3           # E#VALUE (2 measured)
MEMBER = 3                 # a.b, a[1].b (2 to 3 measured)


class TooDeep(Exception):
    def __init__(self, pos: A.Pos, need: int, what: str):
        super().__init__(what)
        self.pos, self.need, self.what = pos, need, what


def check_body(kind: str, body: list[A.Node]) -> list[TooDeep]:
    """Where MatIEC's parser stack would overflow in a POU body: the first point in each of its statements
    that overflows, in source order (an empty list when the body fits)."""
    base = BODY_BASE.get(kind, 9)
    found = []
    for i, s in enumerate(body):
        d = base + (LATER_STATEMENT if i else 0)
        problem = _first_overflow(s, d, base)
        if problem is not None:
            found.append(problem)
    return found


def _first_overflow(statement: A.Node, depth: int, base: int) -> TooDeep | None:
    # an explicit stack of (node or statement list, pending symbols, innermost statement, its depth),
    # children pushed in reverse so that they come off in source order: no recursion, whatever the input
    todo: list[tuple[object, int, object, int]] = [(statement, depth, statement, depth)]
    while todo:
        node, depth, stmt, stmt_depth = todo.pop()
        if isinstance(node, list):       # a statement list: the first statement has no list before it
            for i, s in reversed(list(enumerate(node))):
                d = depth + (LATER_STATEMENT if i else 0)
                todo.append((s, d, s, d))
            continue
        for child, extra, cost in reversed(_parts(node)):
            if child is None:            # a token: its own cost
                need = depth + extra + cost
                if need > LIMIT:
                    # the nesting of the statements is to blame when the innermost statement would fit
                    # at the top of the body
                    if need - stmt_depth + base <= LIMIT:
                        return TooDeep(stmt.pos, need, "statements")
                    return TooDeep(node.pos, need, "expression")
            else:
                todo.append((child, depth + extra, stmt, stmt_depth))
    return None


def _parts(node) -> list[tuple[object, int, int]]:
    """(child, symbols pending while the child is parsed, 0) for each part of a node, and
    (None, pending, cost) for each token that ends a path."""
    if isinstance(node, A.Expr):
        p = node.paren
        if isinstance(node, A.BinOp):
            return [(node.left, p, 0), (node.right, p + 2, 0)]
        if isinstance(node, A.UnOp):
            return [(node.operand, p + 1, 0)]
        if isinstance(node, A.Call):
            out = [(None, p, 3)]                      # F ( )
            formal = 0
            for i, a in enumerate(node.args):
                named = a.name is not None
                formal += named
                out.append((a.value, p + 2 + (2 if i else 0) + (2 if named else 0), 0))
            return out
        if isinstance(node, A.Index):
            return [(node.base, p, 0)] + [(ix, p + 2 + (2 if i else 0), 0) for i, ix in enumerate(node.indices)]
        if isinstance(node, (A.Member, A.BitAccess, A.Deref)):
            return [(node.base, p, 0), (None, p, MEMBER)]
        if isinstance(node, A.Literal):
            cost = _LITERAL_COST.get(node.kind, TYPED_LITERAL if node.type_name else 1)
            return [(None, p, cost)]
        if isinstance(node, A.EnumLit):
            return [(None, p, ENUM_LITERAL)]
        return [(None, p, 1)]                         # a name, a direct address
    if isinstance(node, A.Assign):
        return [(node.target, 0, 0), (node.value, 2, 0)]
    if isinstance(node, A.CallStmt):
        return _parts(node.call)
    if isinstance(node, A.If):
        out = []
        for i, (cond, body) in enumerate(node.branches):
            # IF expr THEN; ... stmt_list [elsif list] ELSIF expr THEN
            out += [(cond, 1 if i == 0 else 6, 0), (body, 3 if i == 0 else 8, 0)]
        if node.else_body is not None:
            out.append((node.else_body, 6, 0))      # IF expr THEN stmt_list [elsif list] ELSE
        return out
    if isinstance(node, A.Case):
        out = [(node.selector, 1, 0)]
        for k, (labels, body) in enumerate(node.elements):
            before = 3 + (1 if k else 0)                 # CASE expr OF [element list]
            for j, lab in enumerate(labels):
                at = before + (2 if j else 0)            # label list ,
                out.append((None, at, _label_cost(lab.lo)))
                if lab.hi is not None:
                    out.append((None, at + 2, _label_cost(lab.hi)))      # lo ..
            out.append((body, before + 2, 0))            # labels :
        if node.else_body is not None:
            out.append((node.else_body, 5, 0))           # CASE expr OF element list ELSE
        return out
    if isinstance(node, A.For):
        # FOR i := start TO end [BY step] DO
        out = [(None, 1, 1), (node.start, 3, 0), (node.end, 5, 0)]
        if node.step is not None:
            out.append((node.step, 7, 0))
        out.append((node.body, 9 if node.step is not None else 7, 0))
        return out
    if isinstance(node, A.While):
        return [(node.cond, 1, 0), (node.body, 3, 0)]
    if isinstance(node, A.Repeat):
        return [(node.body, 1, 0), (node.cond, 3, 0)]
    return [(None, 0, 2)]                                # EXIT ; RETURN ; pragmas


def _label_cost(v) -> int:
    if isinstance(v, A.EnumLit):
        return ENUM_LITERAL
    if isinstance(v, A.Literal) and v.type_name:
        return TYPED_LITERAL
    return 1

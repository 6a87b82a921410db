"""A small evaluator of the Structured Text subset the ST export emits, built on blark's parse tree.

blark (GPL) parses the text; this module only reads its dataclasses (test-only: the package never
imports blark). The subset: FUNCTION and FUNCTION_BLOCK with VAR_INPUT / VAR_OUTPUT / VAR / VAR_TEMP /
VAR CONSTANT of LREAL, BOOL, DINT and one-dimensional arrays; assignments, IF/ELSIF/ELSE, FOR (BY),
WHILE; arithmetic, comparisons, AND/OR/XOR/NOT; calls of the program's functions and of ABS, SQRT,
LN, EXP, DINT_TO_LREAL. Anything else raises NotImplementedError, so the export cannot slip a
construct past the test. Each node is compiled once into a Python closure; LREAL is Python's float
(IEEE 754 double, the operations in the text's order), DINT a Python int.

``Program(text, real32=True)`` runs ``REAL`` in float32: every REAL variable, array element and function
result is a ``numpy.float32``, a literal combines with it as float32 (NumPy's scalar promotion: a Python
float is weak), so each operation rounds to float32 as a single-precision FPU does. It adds ``TRUNC``
(toward zero, to DINT), ``DINT_TO_REAL`` and array initializers ``[a, b, ...]`` (the REAL block's table).

``plcopen_source(xml)`` rebuilds the ST text of a PLCopen XML (TC6 2.01) project from its XML alone (the
interface's variables, types and initial values; the ST bodies), so that ``Program(plcopen_source(xml))``
runs what a CODESYS-type runtime imports through the same evaluator as the ``.st`` file.
"""

from __future__ import annotations

import math
import operator
import xml.etree.ElementTree as ET

import numpy as np

try:  # the test extra; the tests that use this module skip without it (pytest imports it for doctests too)
    import blark
    from blark import transform as tf
except ImportError:  # pragma: no cover
    blark = tf = None

_BUILTINS = {"ABS": abs, "SQRT": math.sqrt, "LN": math.log, "EXP": math.exp, "DINT_TO_LREAL": float}


def _div(a, b):
    if isinstance(a, int) and isinstance(b, int):
        return int(a / b)  # DINT division truncates toward zero
    return a / b


_BINARY = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": _div, "=": operator.eq, "<>": operator.ne,
           "<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge,
           "AND": lambda a, b: a and b, "OR": lambda a, b: a or b, "XOR": operator.xor}


def _array_thunk(n, zero=0.0, values=None):
    def fresh():
        return list(values) if values is not None else [zero] * n
    return fresh


def _flatten(init):
    """The leaves of blark's (nested) array initializer."""
    if isinstance(init, tf.ArrayInitialization):
        return [leaf for element in init.elements for leaf in _flatten(element)]
    if isinstance(init, tf.ArrayInitialElement):
        if init.count is not None:
            raise NotImplementedError("repeated array elements")
        return _flatten(init.element)
    return [init]


def _value_thunk(expr, default):
    def fresh():
        return expr({}) if expr is not None else default
    return fresh


def _float32(thunk):
    """``thunk`` with its result rounded to float32 (a store into a REAL)."""
    def rounded(env):
        return np.float32(thunk(env))
    return rounded


_TC6 = "{http://www.plcopen.org/xml/tc6_0201}"
_XHTML_P = "{http://www.w3.org/1999/xhtml}p"
_TC6_SECTIONS = {"inputVars": "VAR_INPUT", "outputVars": "VAR_OUTPUT", "localVars": "VAR", "tempVars": "VAR_TEMP"}


def _tc6_type(node) -> str:
    (t,) = list(node)
    name = t.tag.removeprefix(_TC6)
    if name != "array":
        return name
    (dim,) = t.findall(f"{_TC6}dimension")
    (base,) = list(t.find(f"{_TC6}baseType"))
    return f"ARRAY[{dim.get('lower')}..{dim.get('upper')}] OF {base.tag.removeprefix(_TC6)}"


def _tc6_value(node) -> str:
    simple = node.find(f"{_TC6}simpleValue")
    if simple is not None:
        return simple.get("value")
    values = node.findall(f"{_TC6}arrayValue/{_TC6}value/{_TC6}simpleValue")
    return "[" + ", ".join(v.get("value") for v in values) + "]"


def plcopen_source(xml: str) -> str:
    """The ST text of the POUs of a PLCopen XML project, read from the XML only (not the package's generator)."""
    root = ET.fromstring(xml.encode())
    parts = []
    for pou in root.iter(f"{_TC6}pou"):
        kind = {"function": "FUNCTION", "functionBlock": "FUNCTION_BLOCK"}[pou.get("pouType")]
        interface = pou.find(f"{_TC6}interface")
        returns = interface.find(f"{_TC6}returnType")
        lines = [f"{kind} {pou.get('name')}" + (f" : {_tc6_type(returns)}" if returns is not None else "")]
        for section in interface:
            tag = section.tag.removeprefix(_TC6)
            if tag == "returnType":
                continue
            lines.append("VAR CONSTANT" if section.get("constant") == "true" else _TC6_SECTIONS[tag])
            for v in section.findall(f"{_TC6}variable"):
                init = v.find(f"{_TC6}initialValue")
                value = f" := {_tc6_value(init)}" if init is not None else ""
                lines.append(f"    {v.get('name')} : {_tc6_type(v.find(f'{_TC6}type'))}{value};")
            lines.append("END_VAR")
        body = pou.find(f"{_TC6}body/{_TC6}ST/{_XHTML_P}").text
        parts.append("\n".join(lines) + "\n" + body + f"END_{kind}\n")
    return "\n".join(parts)


class _Return(Exception):
    pass


class Program:
    """The POUs of one ST source; ``Program(text).block(name)`` is a fresh function-block instance."""

    def __init__(self, source: str, *, real32: bool = False):
        result = blark.parse_source_code(source)
        if result.exception is not None:
            raise result.exception
        self.pous = {str(item.name).upper(): item for item in result.transform().items}
        self._compiled: dict[str, tuple] = {}
        self.real32 = real32
        self._real_names: set[str] = set()  # the REAL names of the POU being compiled (real32 only)
        self._builtins = dict(_BUILTINS)
        if real32:
            self._builtins.update({"DINT_TO_REAL": np.float32, "TRUNC": lambda a: int(math.trunc(float(a))),
                                   "ABS": lambda a: np.float32(abs(a)) if isinstance(a, np.floating) else abs(a)})

    # --- declarations -------------------------------------------------------------------------
    def _declarations(self, pou):
        """[(section, name, initial value thunk)] in order; sections: input, output, var, temp, constant."""
        out = []
        for block in pou.declarations:
            kind = {tf.InputDeclarations: "input", tf.OutputDeclarations: "output",
                    tf.TemporaryVariableDeclarations: "temp", tf.FunctionVariableDeclarations: "var",
                    tf.VariableDeclarations: "var"}.get(type(block))
            if kind is None:
                raise NotImplementedError(type(block).__name__)
            if kind == "var" and getattr(block, "attrs", None) is not None and "CONSTANT" in str(block.attrs).upper():
                kind = "constant"
            for item in block.items:
                init = item.init
                if isinstance(init, tf.ArrayTypeInitialization):
                    (rng,) = init.spec.subranges
                    lo, hi = int(str(rng.start.value)), int(str(rng.stop.value))
                    real = self.real32 and str(init.spec.type.type_name).upper() == "REAL"
                    if lo != 0 or (init.value is not None and not self.real32):
                        raise NotImplementedError("array bounds other than 0..n or an array initializer")
                    values = None
                    if init.value is not None:
                        values = [self._expr(leaf)({}) for leaf in _flatten(init.value)]
                        if len(values) != hi + 1:
                            raise ValueError(f"array initializer: expected {hi + 1} values, found {len(values)}")
                        values = [np.float32(v) for v in values] if real else values
                    thunk = _array_thunk(hi + 1, np.float32(0.0) if real else 0.0, values)
                else:
                    type_name = str(init.spec.type).upper()
                    real = self.real32 and type_name == "REAL"
                    default = {"LREAL": 0.0, "REAL": 0.0, "BOOL": False, "DINT": 0, "INT": 0}[type_name]
                    thunk = _value_thunk(self._expr(init.value) if init.value is not None else None, default)
                    if real:
                        thunk = (lambda fresh: lambda: np.float32(fresh()))(thunk)
                for var in item.variables:
                    name = str(var.variable.name).upper()
                    if real:
                        self._real_names.add(name)
                    out.append((kind, name, thunk))
        return out

    def _pou(self, name):
        key = name.upper()
        if key not in self._compiled:
            pou = self.pous[key]
            outer = self._real_names
            self._real_names = set()
            if self.real32 and str(getattr(pou, "return_type", "") or "").upper() == "REAL":
                self._real_names.add(key)  # the function's result
            decls = self._declarations(pou)
            self._compiled[key] = (decls, self._statements(pou.body))
            self._real_names = outer
        return self._compiled[key]

    def block(self, name: str) -> Block:
        return Block(self, name)

    def call_function(self, name: str, args: list):
        decls, body = self._pou(name)
        env = {}
        inputs = [n for kind, n, _ in decls if kind == "input"]
        if len(args) != len(inputs):
            raise TypeError(f"{name}: expected {len(inputs)} arguments, found {len(args)}")
        for kind, n, thunk in decls:
            env[n] = thunk()
        env.update(zip(inputs, args))
        env[name.upper()] = 0.0
        try:
            body(env)
        except _Return:
            pass
        return env[name.upper()]

    # --- statements ---------------------------------------------------------------------------
    def _statements(self, node):
        if node is None:
            return lambda env: None
        stmts = [self._statement(s) for s in node.statements]

        def run(env):
            for s in stmts:
                s(env)
        return run

    def _statement(self, s):
        if isinstance(s, tf.AssignmentStatement):
            (target,) = s.variables
            value = self._expr(s.expression)
            return self._store(target, value)
        if isinstance(s, tf.IfStatement):
            branches = [(self._expr(s.if_expression), self._statements(s.statements))]
            branches += [(self._expr(b.if_expression), self._statements(b.statements)) for b in s.else_ifs]
            other = self._statements(s.else_clause.statements) if s.else_clause else (lambda env: None)

            def run_if(env):
                for cond, body in branches:
                    if cond(env):
                        body(env)
                        return
                other(env)
            return run_if
        if isinstance(s, tf.ForStatement):
            name = str(s.control.name).upper()
            lo, hi = self._expr(s.from_), self._expr(s.to)
            step = self._expr(s.step) if s.step is not None else (lambda env: 1)
            body = self._statements(s.statements)

            def run_for(env):
                i, end, by = lo(env), hi(env), step(env)
                env[name] = i
                while (by > 0 and env[name] <= end) or (by < 0 and env[name] >= end):
                    body(env)
                    env[name] += by
            return run_for
        if isinstance(s, tf.WhileStatement):
            cond, body = self._expr(s.expression), self._statements(s.statements)

            def run_while(env):
                while cond(env):
                    body(env)
            return run_while
        if isinstance(s, tf.ReturnStatement):
            def run_return(env):
                raise _Return
            return run_return
        raise NotImplementedError(type(s).__name__)

    def _store(self, target, value):
        if isinstance(target, tf.SimpleVariable):
            name = str(target.name).upper()
            if name in self._real_names:
                value = _float32(value)

            def store(env):
                env[name] = value(env)
            return store
        if isinstance(target, tf.MultiElementVariable):
            array, index = self._element(target)
            if array in self._real_names:
                value = _float32(value)

            def store_element(env):
                env[array][index(env)] = value(env)
            return store_element
        raise NotImplementedError(type(target).__name__)

    def _element(self, node):
        (sub,) = node.elements
        (index,) = sub.subscripts
        return str(node.name.name).upper(), self._expr(index)

    # --- expressions --------------------------------------------------------------------------
    def _expr(self, e):
        if isinstance(e, tf.Real):
            value = float(str(e.value))
            return lambda env: value
        if isinstance(e, tf.Integer):
            ivalue = int(str(e.value))
            return lambda env: ivalue
        if isinstance(e, tf.Boolean):
            bvalue = str(e.value).upper() == "TRUE"
            return lambda env: bvalue
        if isinstance(e, tf.SimpleVariable):
            name = str(e.name).upper()
            return lambda env: env[name]
        if isinstance(e, tf.MultiElementVariable):
            array, index = self._element(e)
            return lambda env: env[array][index(env)]
        if isinstance(e, tf.ParenthesizedExpression):
            return self._expr(e.expr)
        if isinstance(e, tf.UnaryOperation):
            inner, op = self._expr(e.expr), str(e.op).upper()
            if op == "-":
                return lambda env: -inner(env)
            if op == "NOT":
                return lambda env: not inner(env)
            raise NotImplementedError(op)
        if isinstance(e, tf.BinaryOperation):
            left, right, fn = self._expr(e.left), self._expr(e.right), _BINARY[str(e.op).upper()]
            return lambda env: fn(left(env), right(env))
        if isinstance(e, tf.FunctionCall):
            name = str(e.name.name).upper()
            if any(p.name is not None for p in e.parameters):
                raise NotImplementedError("formal (named) arguments")
            args = [self._expr(p.value) for p in e.parameters]
            if name in self._builtins:
                fn = self._builtins[name]
                return lambda env: fn(*(a(env) for a in args))
            if name not in self.pous:
                raise NotImplementedError(f"function {name}")
            return lambda env: self.call_function(name, [a(env) for a in args])
        raise NotImplementedError(type(e).__name__)


class Block:
    """One instance of a FUNCTION_BLOCK: its VAR state kept between calls, VAR_TEMP fresh at each."""

    def __init__(self, program: Program, name: str):
        self.decls, self.body = program._pou(name)
        self.env = {n: thunk() for kind, n, thunk in self.decls if kind != "temp"}
        self.inputs = [n for kind, n, _ in self.decls if kind == "input"]
        self.outputs = [n for kind, n, _ in self.decls if kind == "output"]
        self.temps = [(n, thunk) for kind, n, thunk in self.decls if kind == "temp"]

    def __call__(self, *args):
        """Call with the inputs in declaration order; returns the outputs as a dict (upper-case names)."""
        self.env.update(zip(self.inputs, args, strict=True))
        for n, thunk in self.temps:
            self.env[n] = thunk()
        self.body(self.env)
        return {n: self.env[n] for n in self.outputs}

"""The Taylor recurrences of functions of a series, emitted as LLVM IR over vectors of any width.

Both generated series use them: the batch lanes (``batch_taylor``: a lane per trajectory) and the single trajectory
(``taylor_series``: one lane, ``<1 x double>``). Recurrences (x, y the arguments, f the result, Σ_j a sum over j;
Moore 1966; Jorba & Zou, Exp. Math. 14, 2005, §3; Haro et al. 2016, §2.1):

  x/y: f_k = (x_k − Σ_{j<k} f_j y_{k−j}) / y_0;  √x: f_k = (x_k − Σ_{j=1..k−1} f_j f_{k−j}) / (2 f_0);
  exp: f_k = (1/k) Σ_{j=1..k} j x_j f_{k−j};  log: f_k = (x_k − (1/k) Σ_{j=1..k−1} j f_j x_{k−j}) / x_0;
  sin, cos as a pair: s_k = (1/k) Σ j x_j c_{k−j},  c_k = −(1/k) Σ j x_j s_{k−j};
  tan, tanh: f' = g x' with g = 1 ± f² (an auxiliary series);  arctan: f' (1 + x²) = x';
  arctan2(y, x): f' (x² + y²) = x y' − y x';  x^a (a constant): x f' = a f x', i.e.
  f_k = Σ_{j<k} (a(k−j) − j) x_{k−j} f_j / (k x_0);  |x|: sign(x_0) x_k, exact wherever x_0 ≠ 0.

The divisions make x/y, √x, log x, x^a (a not an integer) and arctan2 (at x = y = 0) singular where their argument's
value is 0 (as the functions themselves, or their derivatives, are): there the coefficients are inf/NaN and the
integrator stops with its one-sentence non-finite error.
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils

from gyrolab.kernels import simd

#: functions whose recurrence needs an auxiliary series: tan, tanh: 1 ± f²; arctan: 1 + x²; arctan2: x² + y²
AUXILIARY = ("tan", "tanh", "arctan", "arctan2")


def work_columns(series: list, skip: tuple[str, ...], start: int = 0) -> dict[tuple, int]:
    """W's columns from ``start`` on: ("u", operand) for every operand of a series whose op is not in ``skip``,
    ("f", series, 0) for a function's result and ("f", series, 1) for a sine's cosine or an auxiliary series."""
    column: dict[tuple, int] = {}
    for i, (op, args, _, _) in enumerate(series):
        if op in skip:
            continue
        for u in args:
            column.setdefault(("u", u), start + len(column))
        if op != "mul":
            column[("f", i, 0)] = start + len(column)
            if op == "sin" or op in AUXILIARY:
                column[("f", i, 1)] = start + len(column)
    return column


class Functions:
    """The order-k coefficient of a function of a series, in every lane of a ``<lanes x double>`` vector: at order 0
    its value (libm's, lane by lane, as the scalar kernel's; sqrt and division exact), at order k ≥ 1 its
    recurrence from the W rows of its operands (0..k) and of itself (0..k−1). Returns {series: value}, the sine's
    cosine as series + 1; stores its rows in W."""

    def __init__(self, b, lanes, k, first, load, store, number):
        self.b, self.lanes, self.k, self.first = b, lanes, k, first
        self.load, self.store, self.number = load, store, number
        self.vec = ir.VectorType(ir.DoubleType(), lanes)
        self.kf = simd.splat(b, b.sitofp(k, ir.DoubleType()), lanes)

    def splat(self, x):
        return ir.Constant(self.vec, [float(x)] * self.lanes)

    def libm(self, name, *xs):
        """The C library's ``name`` lane by lane."""
        b, double = self.b, ir.DoubleType()
        fn = cgutils.get_or_insert_function(b.module, ir.FunctionType(double, [double] * len(xs)), name)
        out = ir.Constant(self.vec, ir.Undefined)
        for lane in range(self.lanes):
            i = ir.Constant(ir.IntType(32), lane)
            out = b.insert_element(out, b.call(fn, [b.extract_element(x, i) for x in xs]), i)
        return out

    def total(self, lo, hi, term):
        """Σ_{j=lo}^{hi−1} term(j) (LLVM integers lo, hi; term returns a vector)."""
        b = self.b
        acc = cgutils.alloca_once_value(b, self.splat(0.0))
        with cgutils.for_range(b, b.sub(hi, lo)) as loop:
            j = b.add(lo, loop.index)
            b.store(b.fadd(b.load(acc), term(j), flags=simd.FUSE), acc)
        return b.load(acc)

    def __call__(self, op, i, args, extra, rows):
        b, k = self.b, self.k
        i64 = k.type
        zero, one = ir.Constant(i64, 0), ir.Constant(i64, 1)
        x = (lambda row: self.load(row, ("u", args[0])))
        y = (lambda row: self.load(row, ("u", args[1]))) if len(args) > 1 else None
        f = (lambda row: self.load(row, ("f", i, 0)))
        g = (lambda row: self.load(row, ("f", i, 1)))  # the cosine or the auxiliary series
        jf = (lambda j: simd.splat(b, b.sitofp(j, ir.DoubleType()), self.lanes))
        mul = (lambda p, q: b.fmul(p, q, flags=simd.FUSE))
        xk, x0 = rows[args[0]], x(zero)
        slots = [cgutils.alloca_once(b, self.vec) for _ in range(2)]
        with b.if_else(self.first) as (start, later):
            with start:
                for slot, value in zip(slots, self._start(op, rows, args, extra)):
                    b.store(value, slot)
            with later:
                if op == "div":
                    s = b.fsub(xk, self.total(zero, k, lambda j: mul(f(j), y(b.sub(k, j)))))
                    values = [b.fdiv(s, y(zero))]
                elif op == "sqrt":
                    s = b.fsub(xk, self.total(one, k, lambda j: mul(f(j), f(b.sub(k, j)))))
                    values = [b.fdiv(s, mul(self.splat(2.0), f(zero)))]
                elif op == "exp":
                    values = [b.fdiv(self.total(one, b.add(k, one), lambda j: mul(mul(jf(j), x(j)), f(b.sub(k, j)))),
                                     self.kf)]
                elif op == "log":
                    s = b.fdiv(self.total(one, k, lambda j: mul(mul(jf(j), f(j)), x(b.sub(k, j)))), self.kf)
                    values = [b.fdiv(b.fsub(xk, s), x0)]
                elif op == "sin":  # (sine, cosine)
                    values = [b.fdiv(self.total(one, b.add(k, one), lambda j: mul(mul(jf(j), x(j)), g(b.sub(k, j)))),
                                     self.kf),
                              b.fneg(b.fdiv(self.total(one, b.add(k, one),
                                                       lambda j: mul(mul(jf(j), x(j)), f(b.sub(k, j)))), self.kf))]
                elif op in ("tan", "tanh"):  # f' = d x', d = 1 ± f²
                    fk = b.fdiv(self.total(one, b.add(k, one), lambda j: mul(mul(jf(j), x(j)), g(b.sub(k, j)))),
                                self.kf)
                    d = b.fadd(self.total(one, k, lambda j: mul(f(j), f(b.sub(k, j)))), mul(self.splat(2.0),
                                                                                            mul(f(zero), fk)))
                    values = [fk, d if op == "tan" else b.fneg(d)]
                elif op == "arctan":  # f' d = x', d = 1 + x²
                    d = self.total(zero, b.add(k, one), lambda j: mul(x(j), x(b.sub(k, j))))
                    s = b.fsub(mul(self.kf, xk), self.total(one, k, lambda j: mul(mul(jf(j), f(j)), g(b.sub(k, j)))))
                    values = [b.fdiv(s, mul(self.kf, g(zero))), d]
                elif op == "arctan2":  # f = atan2(x, y), d = x² + y², f' d = y x' − x y'
                    d = self.total(zero, b.add(k, one),
                                   lambda j: b.fadd(mul(x(j), x(b.sub(k, j))), mul(y(j), y(b.sub(k, j)))))
                    s = self.total(zero, k, lambda j: mul(jf(b.sub(k, j)), b.fsub(mul(y(j), x(b.sub(k, j))),
                                                                                  mul(x(j), y(b.sub(k, j))))))
                    s = b.fsub(s, self.total(one, k, lambda j: mul(mul(jf(j), f(j)), g(b.sub(k, j)))))
                    values = [b.fdiv(s, mul(self.kf, g(zero))), d]
                elif op == "pow":  # x f' = e f x'
                    e = self.number(extra)
                    s = self.total(zero, k, lambda j: mul(mul(b.fsub(mul(e, jf(b.sub(k, j))), jf(j)), x(b.sub(k, j))),
                                                          f(j)))
                    values = [b.fdiv(s, mul(self.kf, x0))]
                elif op == "abs":
                    sign = b.select(b.fcmp_ordered(">", x0, self.splat(0.0)), self.splat(1.0),
                                    b.select(b.fcmp_ordered("<", x0, self.splat(0.0)), self.splat(-1.0),
                                             self.splat(0.0)))
                    values = [mul(sign, xk)]
                else:
                    raise ValueError(f"the Taylor lanes have no recurrence for {op!r}")
                for slot, value in zip(slots, values):
                    b.store(value, slot)
        out = [b.load(slot) for slot in slots]
        self.store(out[0], k, ("f", i, 0))
        if op == "sin" or op in AUXILIARY:
            self.store(out[1], k, ("f", i, 1))
        return {i: out[0], i + 1: out[1]} if op == "sin" else {i: out[0]}

    def _start(self, op, rows, args, extra):
        """A function's order-0 value (and its cosine or auxiliary series)."""
        b = self.b
        x = rows[args[0]]
        square = (lambda v: b.fmul(v, v))
        if op == "div":
            return [b.fdiv(x, rows[args[1]])]
        if op == "sqrt":
            return [simd.vector_call(b, self.vec, "sqrt", x)]
        if op == "sin":
            return [self.libm("sin", x), self.libm("cos", x)]
        if op in ("tan", "tanh"):
            value = self.libm(op, x)
            return [value, (b.fadd if op == "tan" else b.fsub)(self.splat(1.0), square(value))]
        if op == "arctan":
            return [self.libm("atan", x), b.fadd(self.splat(1.0), square(x))]
        if op == "arctan2":
            return [self.libm("atan2", x, rows[args[1]]), b.fadd(square(x), square(rows[args[1]]))]
        if op == "pow":
            return [self.libm("pow", x, self.number(extra))]
        if op == "abs":
            return [simd.vector_call(b, self.vec, "fabs", x)]
        return [self.libm(op, x)]  # exp, log

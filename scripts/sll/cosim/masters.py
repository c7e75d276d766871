"""Co-simulation masters over partners (sll.cosim.partners) and connections
(docs/stack-on-a-floor.md).

    sim = CoSimulation([stack, frame], [
        ("stack.floorForce", "frame.floor2.force", +1, "N"),    # the stack pushes the floor
        ("frame.floor2.accel", "stack.ag", +1, "m/s2"),         # the floor carries the stack
    ])
    run = sim.run(stop=10.0, H=0.005, master="interface-jacobian",
                  record=["frame.floor2.disp", "stack.slip[1]"])

Masters:
- "jacobi": at every communication point read every connected output, set every
  input, step every partner from t to t + H;
- "gauss-seidel": partners step one after the other in `order`; a partner
  takes the inputs of partners already at t + H from their new values (the chord
  between t and t + H, or the newest value held with constant extrapolation);
- extrapolation "constant" (zero-order hold), "linear" (the slope through the
  last two communication points) or "derivative" (the partners' output
  derivatives), handed to partners that take input slopes (FMI 2.0 FMUs that
  canInterpolateInputs, OpenSeesPartner); `consistent` reads an output that
  depends on an input at once after that input was set; `event_aware` rolls
  every partner back to land just past a switch a partner reports (tSwitch);
- "interface-jacobian": for stacks on floors (connections `S.floorForce -> P.X`
  and `P.Y -> S.ag`, gains +1): the stack's `attachedMass` goes into the
  floor partner's mass at X (add_mass), its `slidingForce` (constant between
  switches) is applied as the force, the stack gets the partner's mobility at
  X as `supportMobility`; mass and force are updated at every stick/slip
  switch. No algebraic loop, no added-mass instability. Event handling
  (`events`): "rollback" (every partner can roll back: the floor partner steps
  first, the stack follows with the chord of the floor's acceleration; at a
  switch both go back and step to it), "stack-first" (a partner cannot roll
  back: the stack steps first with the floor acceleration extrapolated, finds
  its switch by early return (FMI 3.0) or tSwitch and its own rollback, then
  the floor partner steps to the switch), "auto" (rollback if every partner
  can, else stack-first), "none" (switches are taken at communication points
  only: for comparison).
A master that cannot run a configuration raises ConfigurationError saying why.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .partners import ConfigurationError, Partner

MASTERS = ("jacobi", "gauss-seidel", "interface-jacobian")
EXTRAPOLATIONS = ("constant", "linear", "derivative")
EVENTS = ("auto", "rollback", "stack-first", "none")
# A switch closer than this fraction of H to the step's start is the one just
# landed on; the landing on a switch reported by tSwitch goes this fraction of H
# past it, so that the switch happens inside the landing step (docs/coupling.md).
SWITCH_SLACK = 1e-6
LANDING = 1e-7


@dataclass(frozen=True)
class Connection:
    """`target` input <- gain * `source` output; names are "partner.port"."""

    source: str
    target: str
    gain: float = 1.0
    unit: str = ""

    @staticmethod
    def of(item) -> "Connection":
        if isinstance(item, Connection):
            return item
        return Connection(*item)

    def split(self, which: str) -> tuple[str, str]:
        name = getattr(self, which)
        partner, dot, port = name.partition(".")
        if not dot or not port:
            raise ConfigurationError(f"connection {self.source} -> {self.target}: {name!r} is not "
                                     "'partner.port'")
        return partner, port


class CoSimulation:
    """Partners and the connections between them; `run` couples them with a master."""

    def __init__(self, partners: list[Partner], connections: list):
        self.partners = {}
        for p in partners:
            if p.name in self.partners:
                raise ConfigurationError(f"two partners are named {p.name!r}")
            self.partners[p.name] = p
        self.connections = [Connection.of(c) for c in connections]
        targets = set()
        for c in self.connections:
            for which in ("source", "target"):
                partner, _ = c.split(which)
                if partner not in self.partners:
                    raise ConfigurationError(f"connection {c.source} -> {c.target}: no partner "
                                             f"{partner!r} (partners: {sorted(self.partners)})")
            if c.target in targets:
                raise ConfigurationError(f"input {c.target} is connected twice")
            targets.add(c.target)
            if not math.isfinite(c.gain):
                raise ConfigurationError(f"connection {c.source} -> {c.target}: gain {c.gain}")

    # ------------------------------------------------------------- helpers
    def _get(self, name: str) -> float:
        partner, _, port = name.partition(".")
        return self.partners[partner].get(port)

    def _set(self, c: Connection, value: float, slope: float):
        partner, port = c.split("target")
        p = self.partners[partner]
        p.set(port, c.gain * value, c.gain * slope if p.takes_slopes else 0.0)

    def _sample(self, t: float, on_grid: bool):
        self.out["time"].append(t)
        self.out["on_grid"].append(on_grid)
        for name in self.record:
            self.out[name].append(self._get(name))

    def _step(self, p: Partner, t: float, h: float, exact: bool = True) -> float:
        reached = p.step(t, h)
        self.steps[p.name] += 1
        if exact and reached < t + h - 1e-12 * max(1.0, t + h):
            raise ConfigurationError(f"{p.name} returned early at {reached:.9g} (step to {t + h:.9g}): "
                                     "this master needs partners created without early return")
        return reached

    # ----------------------------------------------------------------- run
    def run(self, stop: float, H: float, master: str = "jacobi", extrapolation: str = "linear",
            order: list[str] | None = None, events: str = "auto", record=(),
            held_substeps: int = 4, consistent: bool = True, event_aware: bool = False) -> dict:
        """Couples the partners from 0 to `stop` with macro step H (the last
        step is shorter when H does not divide stop). Returns time (every
        communication point, switch landings included), on_grid (which are not
        landings), each recorded "partner.port" as an array, and the cost:
        steps (per partner), rollbacks, landings, seconds. `held_substeps`:
        the interface-Jacobian master steps a stack that holds its inputs (FMI
        3.0) in this many pieces per step, each with the floor acceleration at
        its middle. For Jacobi and Gauss-Seidel: `consistent` (read outputs
        that depend on inputs after those are set, sweeping until nothing
        changes; False: every output read once right after the step, as a
        plain importer does) and `event_aware` (every partner saves its
        state; when one reports a tSwitch inside the step, all go back and
        step to just past it)."""
        if extrapolation == "derivative" and master == "interface-jacobian":
            raise ConfigurationError("extrapolation='derivative' is for jacobi and gauss-seidel")
        if int(held_substeps) < 1:
            raise ConfigurationError(f"held_substeps = {held_substeps}: at least 1")
        self.held_substeps = int(held_substeps)
        if master not in MASTERS:
            raise ConfigurationError(f"master = {master!r}: it must be one of {MASTERS}")
        if extrapolation not in EXTRAPOLATIONS:
            raise ConfigurationError(f"extrapolation = {extrapolation!r}: one of {EXTRAPOLATIONS}")
        if events not in EVENTS:
            raise ConfigurationError(f"events = {events!r}: one of {EVENTS}")
        if not (math.isfinite(H) and 0 < H <= stop):
            raise ConfigurationError(f"H = {H}: it must be > 0 and at most stop = {stop}")
        order = list(order or self.partners)
        if sorted(order) != sorted(self.partners):
            raise ConfigurationError(f"order {order} must name every partner once: {sorted(self.partners)}")
        self.record = list(record)
        for name in self.record:
            partner, dot, _ = name.partition(".")
            if partner not in self.partners or not dot:
                raise ConfigurationError(f"record {name!r}: not 'partner.port' of a partner")
        plan = self._interface_plan(events) if master == "interface-jacobian" else None
        if master != "interface-jacobian":
            for p in self.partners.values():
                if p.returns_early:
                    raise ConfigurationError(f"{p.name} may return early: {master} steps every partner "
                                             "to the same time (create it without early return)")
        self.out = {"time": [], "on_grid": [], **{n: [] for n in self.record}}
        self.steps = {n: 0 for n in self.partners}
        self.rollbacks = self.landings = self.corrections = 0
        for p in self.partners.values():
            p.start(0.0, stop)
        started = time.perf_counter()
        n_steps = math.ceil(stop / H - 1e-9)
        if plan is None:
            self._classic(stop, H, n_steps, master, extrapolation, order, consistent, event_aware)
        else:
            self._interface(stop, H, n_steps, plan, extrapolation)
        result = {k: np.array(v) for k, v in self.out.items()}
        result.update(steps=dict(self.steps), rollbacks=self.rollbacks, landings=self.landings,
                      corrections=self.corrections,
                      seconds=time.perf_counter() - started, master=master, H=H)
        return result

    # ---------------------------------------------- jacobi and gauss-seidel
    def _exchange(self, t: float, sources: list[str], extrapolation: str, consistent: bool, previous):
        """Values (and slopes) of every connected output at t, set on the
        inputs. `consistent`: read and set again until no value changes, so
        that an output that depends on an input at once (a storey's apAbs on
        its Fext) is read after that input was set (as many sweeps as the
        longest chain of such dependencies, plus one that changes nothing);
        otherwise every output is read once, before any input is set (as a
        plain importer does). Slopes: "linear" through the last two
        communication points, "derivative" from the partners' output
        derivatives (swept likewise: a derivative may depend on an input's
        slope), "constant" none."""
        y = {s: self._get(s) for s in sources}
        if consistent:
            for _ in range(len(self.partners) + 1):
                for c in self.connections:
                    self._set(c, y[c.source], 0.0)
                again = {s: self._get(s) for s in sources}
                if again == y:
                    break
                y = again
        slope = dict.fromkeys(sources, 0.0)
        if extrapolation == "linear" and previous is not None:
            tp, yp = previous
            slope = {s: (y[s] - yp[s]) / (t - tp) for s in sources}
        elif extrapolation == "derivative":
            for _ in range(len(self.partners) + 1):
                for c in self.connections:
                    self._set(c, y[c.source], slope[c.source])
                again = {s: self._derivative(s) for s in sources}
                if again == slope:
                    break
                slope = again
        for c in self.connections:
            self._set(c, y[c.source], slope[c.source])
        return y, slope

    def _derivative(self, name: str) -> float:
        partner, _, port = name.partition(".")
        return self.partners[partner].output_derivative(port)

    def _classic_step(self, t, h, y0, slope, master, extrapolation, order, landing=False):
        """Every partner from t to t + h. A landing (event-aware) steps every
        partner from the values at t: a Gauss-Seidel chord would reach across
        the switch's jump."""
        if master == "jacobi" or landing:
            for c in self.connections:
                self._set(c, y0[c.source], slope[c.source])
            for p in self.partners.values():
                self._step(p, t, h)
            return
        done = set()
        for name in order:
            p = self.partners[name]
            for c in self.connections:
                if c.split("target")[0] != name:
                    continue
                if c.split("source")[0] in done:
                    y1 = self._get(c.source)
                    if extrapolation == "constant" or not p.takes_slopes:
                        self._set(c, y1, 0.0)
                    else:
                        self._set(c, y0[c.source], (y1 - y0[c.source]) / h)
                else:
                    self._set(c, y0[c.source], slope[c.source])
            self._step(p, t, h)
            done.add(name)

    def _classic(self, stop, H, n_steps, master, extrapolation, order, consistent=True, event_aware=False):
        sources = sorted({c.source for c in self.connections})
        partners = list(self.partners.values())
        switching = [p for p in partners if self._has(p, "tSwitch")]
        if event_aware:
            cannot = [p.name for p in partners if not p.can_rollback]
            if cannot:
                raise ConfigurationError(f"event_aware: {', '.join(cannot)} cannot roll back (save/restore)")
            if not switching:
                raise ConfigurationError("event_aware: no partner has a tSwitch output")
        previous = None
        t, k = 0.0, 0
        self._sample(t, True)
        while k < n_steps:
            end = min((k + 1) * H, stop)
            y0, slope = self._exchange(t, sources, extrapolation, consistent, previous)
            previous = (t, y0)
            if not event_aware:
                self._classic_step(t, end - t, y0, slope, master, extrapolation, order)
                t, k = end, k + 1
                self._sample(t, True)
                continue
            saved = {p.name: p.save() for p in partners}
            self._classic_step(t, end - t, y0, slope, master, extrapolation, order)
            first = min(p.get("tSwitch") for p in switching)
            if t + SWITCH_SLACK * H < first < end - SWITCH_SLACK * H:
                # A switch inside: every partner back to t, then to just past
                # the switch with the same inputs, so that it happens under
                # the inputs that predicted it (docs/coupling.md).
                for p in partners:
                    p.restore(saved[p.name])
                self.rollbacks += 1
                landing = first + LANDING * H
                self._classic_step(t, landing - t, y0, slope, master, extrapolation, order, landing=True)
                t = landing
                self._sample(t, False)
                previous = None  # a slope through the switch means nothing
            else:
                t, k = end, k + 1
                self._sample(t, True)
            for p in partners:
                p.free(saved[p.name])

    # ---------------------------------------------------- interface Jacobian
    def _interface_plan(self, events: str) -> dict:
        """The stacks on floors in the connections, checked: which stack, which
        floor partner and force port, which acceleration output drives it."""
        stacks = {}
        for c in self.connections:
            sp, sport = c.split("source")
            tp, tport = c.split("target")
            if sport == "floorForce":
                stacks.setdefault(sp, {})["force"] = (c, tp, tport)
            elif tport == "ag" and self._is_stack(tp):
                stacks.setdefault(tp, {})["accel"] = (c, sp, sport)
            else:
                raise ConfigurationError(
                    f"interface-jacobian couples stacks to floors only (S.floorForce -> P.force "
                    f"port, P.acceleration -> S.ag); {c.source} -> {c.target} is neither")
        if not stacks:
            raise ConfigurationError("interface-jacobian: no stack (no connection from S.floorForce)")
        plan = []
        floors_used = set()
        for name, links in stacks.items():
            if set(links) != {"force", "accel"}:
                missing = ({"force", "accel"} - set(links)).pop()
                raise ConfigurationError(f"interface-jacobian: stack {name!r} has no {missing} connection "
                                         "(it needs S.floorForce -> P.<force port> and P.<accel> -> S.ag)")
            (cf, fp, fport), (ca, ap, aport) = links["force"], links["accel"]
            if fp != ap:
                raise ConfigurationError(f"interface-jacobian: stack {name!r} pushes {fp!r} but is "
                                         f"carried by {ap!r}: they must be the same partner")
            for c in (cf, ca):
                if c.gain != 1.0:
                    raise ConfigurationError(
                        f"interface-jacobian: {c.source} -> {c.target} has gain {c.gain}; the master "
                        "moves the stack's attached mass into the floor, which holds for +1 only "
                        "(the floor takes +floorForce and carries the stack with its own acceleration)")
            stack, floor = self.partners[name], self.partners[fp]
            for port in ("attachedMass", "slidingForce"):
                if not self._has(stack, port):
                    raise ConfigurationError(f"interface-jacobian: stack {name!r} has no output {port!r} "
                                             "(StackOnFloor.fmu's interface)")
            if not floor.can_add_mass:
                raise ConfigurationError(
                    f"interface-jacobian: partner {fp!r} cannot add mass at {fport!r} (no add_mass): the "
                    "master moves the stack's attached mass into the floor; use jacobi or gauss-seidel "
                    "with it, or a partner with add_mass (OpenSeesPartner, a model of your own)")
            if (fp, fport) in floors_used:
                raise ConfigurationError(f"interface-jacobian: two stacks on {fp}.{fport}: one stack per floor")
            floors_used.add((fp, fport))
            plan.append({"stack": stack, "floor": floor, "force": fport, "accel": aport,
                         "mass": None, "sliding": None, "impulse": 0.0})
        everyone = list(self.partners.values())
        if events == "auto":
            events = "rollback" if all(p.can_rollback for p in everyone) else "stack-first"
        if events == "rollback":
            cannot = [p.name for p in everyone if not p.can_rollback]
            if cannot:
                raise ConfigurationError(f"events='rollback': {', '.join(cannot)} cannot roll back (save/"
                                         "restore); use events='stack-first', which steps the stack first "
                                         "and the other partners to its switch")
        if events in ("rollback", "stack-first"):
            for entry in plan:
                s = entry["stack"]
                if not (s.returns_early or (s.can_rollback and self._has(s, "tSwitch"))):
                    raise ConfigurationError(
                        f"events={events!r}: stack {s.name!r} can neither return early at a switch "
                        "(FMI 3.0) nor roll back to land on its tSwitch; use events='none'")
        if len(plan) > 1 and events == "stack-first" and not all(e["stack"].can_rollback for e in plan):
            raise ConfigurationError("events='stack-first' with several stacks: every stack must roll back "
                                     "(a stack that switches first sets the time the others go back to)")
        return {"entries": plan, "events": events}

    def _is_stack(self, name: str) -> bool:
        return self._has(self.partners[name], "floorForce")

    @staticmethod
    def _has(p: Partner, port: str) -> bool:
        names = getattr(p, "vars", None)
        if names is not None:
            return port in names
        try:
            p.get(port)
            return True
        except Exception:
            return False

    def _sync(self, plan, t: float):
        """Consistent values at t: the stack's attached mass and sliding force
        (the mode it shows at t) to the floor first, then the floor's
        acceleration with them to the stack, again until the mode no longer
        changes (a switch moves mass between them, which changes the floor's
        acceleration). The order matters after a landing on a switch: the
        stack shows the step's left limit (say a block that came to rest and
        stuck under the support's law); an `ag` set on it re-references the
        law to that mode (a0 = ag), so the floor's acceleration without the
        attached mass (the old mode's) would break the stick at once, and the
        master would never add the mass (docs/stack-on-a-floor.md)."""
        entries = plan["entries"]
        self._floor_from_stacks(entries)
        for _ in range(6):
            for e in entries:
                e["stack"].set("ag", e["floor"].get(e["accel"]), 0.0)
            if not self._floor_from_stacks(entries):
                return

    @staticmethod
    def _floor_from_stacks(entries) -> bool:
        """Each stack's attached mass and sliding force into its floor partner
        where they changed; whether any did."""
        changed = False
        for e in entries:
            mass = e["stack"].get("attachedMass")
            sliding = e["stack"].get("slidingForce")
            if mass != e["mass"]:
                e["floor"].add_mass(e["force"], mass)
                e["mass"], changed = mass, True
            if sliding != e["sliding"]:
                e["floor"].set(e["force"], sliding, 0.0)
                e["sliding"], changed = sliding, True
        return changed

    def _switch_time(self, stack: Partner, t: float, end: float, reached: float, H: float) -> float:
        """Where the stack's step from t should have stopped: its early return,
        or just past its tSwitch, or `end`."""
        slack = SWITCH_SLACK * H
        if reached < end - slack:
            return reached
        if self._has(stack, "tSwitch"):
            ts = stack.get("tSwitch")
            if t + slack < ts < end - slack:  # NaN (no switch) compares False
                return ts + LANDING * H
        return end

    def _stack_step(self, stack: Partner, t: float, h: float, value: float, slope: float) -> float:
        """Steps a stack from t by h with the floor's acceleration value + slope
        (t' - t): as value and slope to a stack that takes input slopes; to one
        that holds its inputs (FMI 3.0), in `held_substeps` pieces, each with
        the acceleration at its middle (exact velocity increments for a linear
        acceleration). Returns the time reached: an early return stops short,
        and so does a piece whose new value switches the stack at its start."""
        if stack.takes_slopes:
            stack.set("ag", value, slope)
            return self._step(stack, t, h, exact=False)
        n = self.held_substeps
        here = t
        for i in range(n):
            end = t + h * (i + 1) / n if i < n - 1 else t + h
            before = (stack.get("attachedMass"), stack.get("slidingForce")) if i else None
            stack.set("ag", value + slope * (0.5 * (here + end) - t), 0.0)
            if i and (stack.get("attachedMass"), stack.get("slidingForce")) != before:
                return here  # the new value switched the stack at the piece's start: stop there
            reached = self._step(stack, here, end - here, exact=False)
            if reached < end - 1e-12 * max(1.0, end):
                return reached
            here = reached
        return here

    def _interface(self, stop, H, n_steps, plan, extrapolation):
        entries, events = plan["entries"], plan["events"]
        for e in entries:
            if self._has(e["stack"], "supportMobility"):
                e["stack"].set("supportMobility", e["floor"].mobility(e["force"]), 0.0)
        partners = list(self.partners.values())
        floors = list({id(e["floor"]): e["floor"] for e in entries}.values())
        stacks = [e["stack"] for e in entries]
        t, k = 0.0, 0
        self._sync(plan, t)
        self._sample(t, True)
        history = None  # (t, floor accelerations) at the last communication point
        chords = None  # the floor accelerations' slopes over the last step (stack-first)
        while k < n_steps:
            end = min((k + 1) * H, stop)
            self._sync(plan, t)
            for e in entries:
                if e["impulse"]:
                    e["floor"].set(e["force"], e["sliding"] + e["impulse"] / (end - t), 0.0)
                    e["impulse"], e["sliding"] = 0.0, None  # the next sync sets the force again
            a0 = [e["floor"].get(e["accel"]) for e in entries]
            if events == "rollback":
                saved = {p.name: p.save() for p in partners}
                for f in floors:
                    self._step(f, t, end - t)
                a1 = [e["floor"].get(e["accel"]) for e in entries]
                slopes = [(b - a) / (end - t) for a, b in zip(a0, a1)]
                reached = [self._stack_step(e["stack"], t, end - t, a, sl) for e, a, sl in zip(entries, a0, slopes)]
                t1 = min(self._switch_time(s, t, end, r, H) for s, r in zip(stacks, reached))
                if t1 < end:
                    self.rollbacks += 1
                    self.landings += 1
                    for f in floors:
                        f.restore(saved[f.name])
                        self._step(f, t, t1 - t)
                    for e, s, r, a, sl in zip(entries, stacks, reached, a0, slopes):
                        if abs(r - t1) > 1e-12 * max(1.0, t1):  # did not stop there itself
                            s.restore(saved[s.name])
                            self._stack_step(s, t, t1 - t, a, sl)
                for p in partners:
                    p.free(saved[p.name])
            else:
                if extrapolation == "linear" and history is not None:
                    slopes = [(a - b) / (t - history[0]) for a, b in zip(a0, history[1])]
                elif extrapolation == "linear" and chords is not None:
                    # Just after a landing: the floor acceleration's slope over
                    # the step that led to it (a jump of the acceleration at a
                    # switch leaves its slope nearly unchanged; holding it would
                    # miss a switch just after).
                    slopes = list(chords)
                else:
                    slopes = [0.0] * len(entries)
                saved = {s.name: s.save() for s in stacks if s.can_rollback and events == "stack-first"}
                reached = [self._stack_step(e["stack"], t, end - t, a, sl) for e, a, sl in zip(entries, a0, slopes)]
                t1 = end
                if events == "stack-first":
                    t1 = min(self._switch_time(s, t, end, r, H) for s, r in zip(stacks, reached))
                    for e, s in zip(entries, stacks):
                        ts = s.get("tSwitch") if self._has(s, "tSwitch") else math.nan
                        if (t1 == end and t <= ts <= t + SWITCH_SLACK * H
                                and (s.get("attachedMass"), s.get("slidingForce")) != (e["mass"], e["sliding"])):
                            # A switch at the very start of the step, in a mode
                            # that did not show it at t: the end of a creep (each
                            # redo with the chord finds the switch a little after
                            # the prediction's). Land just past it.
                            t1 = ts + LANDING * H
                    if t1 < end:
                        self.landings += 1
                elif min(reached) < end - 1e-12 * max(1.0, end):
                    raise ConfigurationError("events='none' needs stacks created without early return")
                for f in floors:
                    self._step(f, t, t1 - t)
                if saved and len(saved) == len(stacks):
                    # The floor went to t1 with the exact mass and force: redo
                    # the stacks' step with the chord of its acceleration (second
                    # order), instead of the extrapolation that found t1.
                    a1 = [e["floor"].get(e["accel"]) for e in entries]
                    chords = [(b - a) / (t1 - t) for a, b in zip(a0, a1)]
                    for e, a, b in zip(entries, a0, a1):
                        s = e["stack"]
                        s.restore(saved[s.name])
                        self.rollbacks += 1
                        chord = (b - a) / (t1 - t)
                        here, first = t, t1
                        while here < t1:  # an early return may stop short (if only by rounding)
                            here = self._stack_step(s, here, t1 - here, a + chord * (here - t), chord)
                            first = min(first, self._switch_time(s, t, t1, here, H))
                        if first < t1 - SWITCH_SLACK * H:
                            # The redo switched at `first`, before t1, where the
                            # floor kept the old mass and force: the momentum it
                            # missed goes to it over the next step.
                            mass, sliding = s.get("attachedMass"), s.get("slidingForce")
                            self.corrections += 1
                            e["impulse"] += (-(mass - e["mass"]) * b + sliding - e["sliding"]) * (t1 - first)
                elif t1 < end:  # no redo: the stacks that went past t1 go back to it
                    for e, s, r, a, sl in zip(entries, stacks, reached, a0, slopes):
                        if abs(r - t1) > 1e-12 * max(1.0, t1):
                            self.rollbacks += 1
                            s.restore(saved[s.name])
                            self._stack_step(s, t, t1 - t, a, sl)
                for s in stacks:
                    if s.name in saved:
                        s.free(saved[s.name])
            # A slope through a switch means nothing: the history restarts there.
            # (a0 was read after the values at t were made consistent, so the
            # history may start at a landing, but not end at one.)
            history = (t, a0) if t1 == end else None
            t = t1
            if t1 == end:
                k += 1
            self._sync(plan, t)
            self._sample(t, t1 == end)

"""A co-simulation master library: couple a stack of sliding blocks
(StackOnFloor.fmu) with any structural model's floor (an OpenSees frame, an
FMU, a model of your own), or FMUs with each other (docs/stack-on-a-floor.md).

    from sll.cosim import CoSimulation, FMUPartner, OpenSeesPartner
    stack = FMUPartner("stack", "target/fmu/StackOnFloor.fmu",
                       {"nBlocks": 2, "m[1]": 500, "m[2]": 250, "mus[1]": 0.2, "muk[1]": 0.15})
    frame = OpenSeesPartner("frame", build_frame, floors={"floor2": 2}, ground=(t, ag))
    sim = CoSimulation([stack, frame], [("stack.floorForce", "frame.floor2.force", +1, "N"),
                                         ("frame.floor2.accel", "stack.ag", +1, "m/s2")])
    run = sim.run(stop=t[-1], H=0.005, master="interface-jacobian",
                  record=["frame.floor2.disp", "stack.slip[1]"])

partners: the protocol (`Partner`), `FMUPartner` (fmpy, FMI 2.0 and 3.0),
`OpenSeesPartner` (openseespy). masters: `Connection`, `CoSimulation` (Jacobi,
Gauss-Seidel, the interface-Jacobian master). ssp: the two-FMU building as an
SSP file.
"""

from .masters import EVENTS, EXTRAPOLATIONS, MASTERS, CoSimulation, Connection
from .partners import ConfigurationError, FMUPartner, NotSupported, OpenSeesPartner, Partner

__all__ = ["CoSimulation", "Connection", "ConfigurationError", "FMUPartner", "MASTERS", "EVENTS",
           "EXTRAPOLATIONS", "NotSupported", "OpenSeesPartner", "Partner"]

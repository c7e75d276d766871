"""What the design codes would have an engineer count as seismic mass of a live load.

The share of the design live (imposed) load that each code adds to the seismic
weight, for an occupancy, with the clauses and factors used. These are the
codes' simplest rules for the seismic weight of a floor; national annexes,
local amendments and project specifications can change them, and the values
below were entered from the codes' texts as the comments say (`confirmed`:
whether a stored public text seen while writing this module states the value).
The engineer must check them against the edition in force.

The comparison in advise.py treats the stack's mass as the live load the codes
speak of (the load present when the earthquake comes): the code's share of it,
rigidly attached, against the share the friction actually mobilises.
"""

from __future__ import annotations

OCCUPANCIES = ("storage", "office", "residential", "shopping")
IS_THRESHOLD = 3.0  # kN/m2: IS 1893 (Part 1):2016 Table 10's boundary


def shares(occupancy: str = "storage", imposed_load: float | None = None,
           correlated_storeys: bool = True) -> list[dict]:
    """Per code: code, clause, share (of the live load, 0-1), factors (words),
    confirmed, note. `imposed_load`: the design imposed floor load in kN/m2 (IS 1893
    needs it; default: 5.0 for storage, 2.0 for office and residential, 4.0 for
    shopping). `correlated_storeys`: EN 1998-1 Table 4.2 for categories A-C."""
    if occupancy not in OCCUPANCIES:
        raise ValueError(f"occupancy = {occupancy!r}: must be one of {', '.join(OCCUPANCIES)}")
    q = imposed_load if imposed_load is not None else {"storage": 5.0, "office": 2.0, "residential": 2.0,
                                                       "shopping": 4.0}[occupancy]
    if not q > 0:
        raise ValueError(f"imposed load = {q}: must be > 0 (kN/m2)")
    out = []
    # IS 1893 (Part 1):2016, 7.3.1 and Table 10: 25 % of imposed floor loads up to and
    # including 3.0 kN/m2, 50 % above. Not confirmed by a stored text.
    is_share = 0.25 if q <= IS_THRESHOLD else 0.50
    out.append({"code": "IS 1893 (Part 1):2016", "clause": "7.3.1, Table 10", "share": is_share,
                "factors": f"imposed floor load {q:g} kN/m2 {'<=' if q <= IS_THRESHOLD else '>'} "
                           f"{IS_THRESHOLD:g} kN/m2: {100 * is_share:g} % (the roof's imposed load is not counted, "
                           "7.3.2)",
                "confirmed": False})
    # ASCE 7-16, 12.7.2 item 1: in areas used for storage, at least 25 % of the floor live
    # load (exceptions: storage adding at most 5 % to the level's effective seismic weight;
    # public garages and open parking). Other live loads are not counted (partitions aside).
    # The 25 % storage rule is stated in public summaries of 12.7.2 (a vendor's manual, a
    # SEAOC mailing-list thread); the standard's own text was not available.
    asce = 0.25 if occupancy == "storage" else 0.0
    out.append({"code": "ASCE 7-16", "clause": "12.7.2 (1)", "share": asce,
                "factors": ("storage: a minimum of 25 % of the floor live load (unless it adds at most 5 % to the "
                            "level's effective seismic weight)" if occupancy == "storage" else
                            f"{occupancy}: floor live load not included (only storage areas are, and partitions)"),
                "confirmed": occupancy == "storage"})
    # EN 1998-1:2004, 3.2.4(2) and 4.2.4, eq. (4.2): psi_E = phi psi_2. psi_2 from EN 1990
    # Annex A1, Table A1.1 (recommended values: A residential / B office 0.3, D shopping
    # 0.6, E storage 0.8; confirmed by a public summary of EN 1990's recommended values);
    # phi from EN 1998-1 Table 4.2 (categories A-C: 0.8 for storeys with correlated
    # occupancies, 0.5 independently occupied, 1.0 roof; D-F and archives: 1.0; not
    # confirmed by a stored text). Both are nationally determined parameters.
    psi2 = {"storage": 0.8, "office": 0.3, "residential": 0.3, "shopping": 0.6}[occupancy]
    category = {"storage": "E", "office": "B", "residential": "A", "shopping": "D"}[occupancy]
    phi = 1.0 if category in "DE" else (0.8 if correlated_storeys else 0.5)
    out.append({"code": "EN 1998-1:2004", "clause": "3.2.4(2), 4.2.4 eq. (4.2) and Table 4.2; EN 1990 Table A1.1",
                "share": phi * psi2,
                "factors": f"category {category}: psi_E = phi psi_2 = {phi:g} x {psi2:g} (recommended values; "
                           "national annexes may differ)",
                "confirmed": False})
    return out

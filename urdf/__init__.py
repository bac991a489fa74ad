"""Scene models (URDF) of the handover environments, installed as :mod:`sandbox.urdf`.

Plain primitives (boxes and cylinders), no mesh files, so any URDF reader
(PyBullet, a viewer) loads them. Sizes and masses are those of the real
objects; each file's comment says them.

==================  =====================================================================
name                what
==================  =====================================================================
``box``             pencil box, 210 x 85 x 45 mm, 0.25 kg (recorded task ``pencil_box``)
``glasses_case``    hard glasses case, 160 x 65 x 40 mm, 0.12 kg
``tape``            roll of gummed paper tape, 100 mm diameter, 48 mm wide, 0.22 kg
                    (recorded task ``gummed_paper``)
``measuring_tape``  5 m measuring tape, 75 x 40 x 75 mm, 0.30 kg
                    (recorded task ``measurement_tape``)
``screwdriver``     screwdriver, 200 mm, 0.09 kg (recorded task ``screw_driver``)
``table``           table, top 600 x 1200 mm, 740 mm high (origin: top surface centre)
``human_hand``      kinematic human hand and forearm (origin: the tracked hand point,
                    +x along the forearm)
``floor``           6 x 6 m floor slab (origin: top surface centre)
==================  =====================================================================

Objects have their origin at their grasp point, which is also their centre of
mass (inside the handle for the screwdriver), so a simulator's base pose is the
grasp point. Files resolve from a source checkout and from an installed wheel
alike (they are package data).
"""

from __future__ import annotations

from pathlib import Path

#: Handover objects.
OBJECTS = ("box", "glasses_case", "tape", "measuring_tape", "screwdriver")
#: Every model shipped here.
MODELS = (*OBJECTS, "table", "human_hand", "floor")


def path(name: str) -> Path:
    """Absolute path of the URDF file of model ``name`` (one of :data:`MODELS`).

    Raises
    ------
    ValueError
        If ``name`` is not one of :data:`MODELS`.
    FileNotFoundError
        If the file is missing from the installation.
    """
    if name not in MODELS:
        raise ValueError(f"name: expected one of {list(MODELS)}, got {name!r}")
    file = Path(__file__).resolve().with_name(f"{name}.urdf")
    if not file.is_file():
        raise FileNotFoundError(
            f"{file} is missing: the package data of sandbox.urdf was not installed"
        )
    return file

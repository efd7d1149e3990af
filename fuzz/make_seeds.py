#!/usr/bin/env python3
"""Writes the seed corpora fuzz/corpus/fuzz_init/ and fuzz/corpus/fuzz_rig/.

The seeds are small, deterministic and mean the same in the double and the
float build (parameters are patched by field index with precision-independent
value modes; see fuzz/fuzz_common.h and the two targets' headers). Re-run
after changing a field table or an input layout:  python3 fuzz/make_seeds.py
"""

import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))

# Field indices (order of fz_gear_fields / fz_rack_fields / fz_rig_fields).
GEAR = {
    "teeth_ratio": 0,
    "output_shaft_rotates": 1,
    "friction_model": 2,
    "loss_smoothing": 3,
    "efficiency_const": 4,
    "power_threshold": 5,
    "idle_torque": 6,
    "nominal_output_torque": 7,
    "efficiency_nominal": 8,
    "speed_threshold": 9,
    "temperature_count": 10,
    "temperature_vector": 11,
    "efficiency_vector": 12,
    "load_count": 13,
    "load_vector": 14,
    "efficiency_matrix": 15,
    "backlash.enabled": 16,
    "backlash.hard_stop_model": 17,
    "backlash.linear_backlash": 18,
    "backlash.base_radius": 19,
    "backlash.transition_region": 20,
    "backlash.stiffness": 21,
    "backlash.damping": 22,
    "backlash.initial_position": 23,
    "backlash.no_pull": 24,
    "backlash.lock_enabled": 25,
    "viscous_coefficients": 28,
    "thermal_mass": 29,
    "initial_temperature": 30,
}
RACK = {
    "parameterization": 0,
    "pinion_radius": 1,
    "teeth_count": 2,
    "spacing": 3,
    "rack_directionality": 4,
    "friction_model": 5,
    "loss_smoothing": 6,
    "efficiency_const": 7,
    "temperature_count": 8,
    "temperature_vector": 9,
    "efficiency_vector": 10,
    "power_threshold": 11,
    "thermal_mass": 14,
    "backlash.enabled": 16,
    "backlash.hard_stop_model": 17,
    "backlash.stiffness": 21,
    "backlash.lock_enabled": 25,
}
RIG = {
    "dt": 0,
    "base_drive": 1,
    "base_inertia": 2,
    "driven_inertia": 4,
    "load_coulomb_friction": 5,
    "heat_path": 8,
    "temperature_source": 10,
    "accel_filter": 11,
    "contact_substeps": 12,
    "load_breakaway_friction": 13,
    "load_stribeck_speed": 14,
    "compliance_stiffness": 15,
    "compliance_damping": 16,
    "ripple_revolution_amplitude": 17,
    "ripple_revolution_phase": 18,
    "ripple_mesh_amplitude": 19,
    "ripple_mesh_phase": 20,
    "ripple_mesh_teeth": 21,
}


def rec_int(dest, field, value):
    return bytes([dest, field, 0, 1, (value + 4) & 0xFF]) + bytes(7)


def rec_pow10(dest, field, exponent_eighths, elem=0, negative=False):
    """value = +-10^(k/8)"""
    return bytes([dest, field, elem, 2, exponent_eighths & 0xFF, 1 if negative else 0]) + bytes(6)


def rec_frac(dest, field, value, elem=0):
    """value = k/256 for a 16-bit signed k"""
    k = int(round(value * 256)) & 0xFFFF
    return bytes([dest, field, elem, 3, k & 0xFF, k >> 8]) + bytes(6)


def rec_interesting(dest, field, index, elem=0):
    return bytes([dest, field, elem, 1, index]) + bytes(7)


def init_seed(target, records, flags=0, steps=b""):
    return bytes([target | flags, len(records)]) + b"".join(records) + steps


def write(dirname, seeds):
    path = os.path.join(HERE, "corpus", dirname)
    os.makedirs(path, exist_ok=True)
    for old in os.listdir(path):
        if old.startswith("finding-"):
            continue  # inputs of past findings, kept as regression cases
        os.remove(os.path.join(path, old))
    for i, data in enumerate(seeds):
        with open(os.path.join(path, f"seed-{i:02d}"), "wb") as fh:
            fh.write(data)
    print(f"{path}: {len(seeds)} seeds, {sum(len(s) for s in seeds)} bytes")


def main():
    rnd = random.Random(20261121)
    steps = bytes(rnd.randrange(256) for _ in range(96))
    g, k, r = 0, 0, 1  # destination byte: even = block params, odd = rig params
    init = []
    for target in range(4):
        init.append(init_seed(target, [], steps=steps))
    for model in range(1, 5):  # gear friction models
        init.append(init_seed(0, [rec_int(g, GEAR["friction_model"], model)], steps=steps))
        init.append(
            init_seed(
                2,
                [
                    rec_int(g, GEAR["friction_model"], model),
                    rec_int(r, RIG["base_drive"], 1),
                    rec_pow10(r, RIG["base_inertia"], -24),
                ],
                steps=steps,
            )
        )
    for law in range(3):  # backlash, each hard-stop law, gear rig and rack rig
        init.append(
            init_seed(
                2,
                [
                    rec_int(g, GEAR["backlash.enabled"], 1),
                    rec_int(g, GEAR["backlash.hard_stop_model"], law),
                    rec_int(g, GEAR["backlash.lock_enabled"], law == 2),
                ],
                steps=steps,
            )
        )
        init.append(
            init_seed(
                3,
                [
                    rec_int(k, RACK["backlash.enabled"], 1),
                    rec_int(k, RACK["backlash.hard_stop_model"], law),
                    rec_int(r, RIG["base_drive"], law != 0),
                    rec_pow10(r, RIG["base_inertia"], -32),
                ],
                steps=steps,
            )
        )
    init.append(
        init_seed(
            1,
            [rec_int(k, RACK["friction_model"], 3), rec_int(k, RACK["parameterization"], 1)],
            steps=steps,
        )
    )
    init.append(
        init_seed(
            3,
            [
                rec_int(k, RACK["friction_model"], 3),
                rec_int(r, RIG["heat_path"], 1),
                rec_pow10(k, RACK["thermal_mass"], -48),
            ],
            steps=steps,
        )
    )
    # the edges: ratio 1e-3 / 1e3, stiffness 1e9, thermal mass 1e-6, tables of GS_TABLE_MAX
    init.append(
        init_seed(
            2,
            [rec_pow10(g, GEAR["teeth_ratio"], -24), rec_int(g, GEAR["friction_model"], 1)],
            steps=steps,
        )
    )
    init.append(
        init_seed(
            2,
            [
                rec_pow10(g, GEAR["teeth_ratio"], 24),
                rec_int(g, GEAR["backlash.enabled"], 1),
                rec_pow10(g, GEAR["backlash.stiffness"], 72),
            ],
            steps=steps,
        )
    )
    table = [
        rec_int(g, GEAR["friction_model"], 4),
        rec_int(g, GEAR["temperature_count"], 10),
        rec_int(g, GEAR["load_count"], 10),
    ]
    for i in range(10):
        table.append(rec_frac(g, GEAR["temperature_vector"], 250 + 10 * i, elem=i))
        table.append(rec_frac(g, GEAR["load_vector"], 5 * i, elem=i))
        table.append(rec_frac(g, GEAR["efficiency_vector"], 0.9, elem=i))
    for i in range(10):
        for j in range(10):
            table.append(
                rec_frac(g, GEAR["efficiency_matrix"], 0.75 + 0.02 * j - 0.01 * i, elem=10 * i + j)
            )
    init.append(init_seed(0, table[:47], steps=steps))  # at most 47 records per input
    init.append(
        init_seed(
            2,
            [
                rec_int(g, GEAR["friction_model"], 3),
                rec_pow10(g, GEAR["thermal_mass"], -48),
                rec_int(r, RIG["heat_path"], 1),
            ],
            steps=steps,
        )
    )
    # failing inits and NULL arguments
    init.append(init_seed(0, [rec_interesting(g, GEAR["teeth_ratio"], 20)]))  # NaN
    init.append(
        init_seed(
            1, [rec_int(k, RACK["temperature_count"], 11), rec_int(k, RACK["friction_model"], 3)]
        )
    )
    init.append(init_seed(2, [rec_interesting(r, RIG["dt"], 0)], flags=4))  # dt 0, err NULL
    init.append(init_seed(3, [], flags=0x18))  # NULL model
    init.append(init_seed(2, [], flags=0x38))  # NULL block params
    # the rig terms of physics.md 11: Stribeck, compliance, ripple; then their failing rules
    stribeck = [
        rec_pow10(r, RIG["load_coulomb_friction"], -8),
        rec_pow10(r, RIG["load_breakaway_friction"], 0),
        rec_pow10(r, RIG["load_stribeck_speed"], -16),
    ]
    ripple = [
        rec_frac(r, RIG["ripple_revolution_amplitude"], 0.25),
        rec_frac(r, RIG["ripple_revolution_phase"], 1.5),
        rec_frac(r, RIG["ripple_mesh_amplitude"], 0.05, elem=1),
        rec_int(r, RIG["ripple_mesh_teeth"], 19),
    ]
    shaft = [
        rec_pow10(r, RIG["base_inertia"], -16),
        rec_pow10(r, RIG["compliance_stiffness"], 24),
        rec_pow10(r, RIG["compliance_damping"], -8),
    ]
    init.append(init_seed(2, stribeck + ripple, steps=steps))
    init.append(
        init_seed(
            3,
            stribeck + [rec_int(r, RIG["base_drive"], 1), rec_pow10(r, RIG["base_inertia"], -32)],
            steps=steps,
        )
    )
    init.append(init_seed(2, shaft + ripple, steps=steps))
    init.append(init_seed(3, shaft + stribeck, steps=steps))
    init.append(
        init_seed(
            2,
            [
                rec_pow10(r, RIG["load_coulomb_friction"], 8),
                rec_pow10(r, RIG["load_breakaway_friction"], 0),
            ],
        )
    )  # breakaway below Coulomb
    init.append(
        init_seed(2, shaft + [rec_int(r, RIG["base_drive"], 1)])
    )  # compliance, torque-driven
    init.append(
        init_seed(3, [rec_frac(r, RIG["ripple_mesh_amplitude"], 0.1)])
    )  # mesh ripple, no teeth
    write("fuzz_init", init)

    rig = []
    for i in range(28):
        c0 = (
            (i & 1)
            | ((i >> 1 & 1) << 1)
            | ((i >> 2 & 1) << 2)
            | ((i % 5 == 0) << 3)
            | (rnd.randrange(4) << 4)
        )
        c1 = i % 5 | rnd.randrange(32) << 3
        c2 = rnd.randrange(256)
        c3 = rnd.randrange(256)
        params = bytes(rnd.randrange(256) for _ in range(120))
        inputs = bytes(rnd.randrange(256) for _ in range(10 * 24))
        rig.append(bytes([c0, c1, c2, c3]) + params + inputs)
    # bit 6: Stribeck friction and ripple; bit 7: compliant shaft (speed-driven rigid rigs)
    for i in range(8):
        c0 = (
            (i & 1) | (((i >> 1) & 1) << 1 if i >= 6 else 0) | (((i >> 2) & 1) << 2 if i < 4 else 0)
        )
        c0 |= 0x40 if i % 3 != 2 else 0
        c0 |= 0x80 if i % 3 != 0 else 0
        c1 = i % 5 | rnd.randrange(32) << 3
        c2 = rnd.randrange(256)
        c3 = rnd.randrange(256)
        params = bytes(rnd.randrange(256) for _ in range(140))
        inputs = bytes(rnd.randrange(256) for _ in range(10 * 24))
        rig.append(bytes([c0, c1, c2, c3]) + params + inputs)
    write("fuzz_rig", rig)


if __name__ == "__main__":
    main()

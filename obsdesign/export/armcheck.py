"""Prove the ``cortex-m4f`` controller on its target: cross-compile, inspect, emulate, count instructions.

:func:`build` compiles the generated ``obsdesign_controller.c`` with ``arm-none-eabi-gcc`` for a
Cortex-M4F (:data:`CFLAGS`), refuses an object that needs any outside symbol (a soft-double helper
``__aeabi_d*``, a libm or libc function: the object must link on its own), reads its flash, RAM and
stack (``arm-none-eabi-size``, ``-fstack-usage``) and links it with a small driver into a flat image.
:func:`emulate` runs the image in the unicorn emulator (Cortex-M4 model, FPU on) over a recorded input
sequence and returns each step's outputs and its instruction count. Both need optional tools: the
Debian package ``gcc-arm-none-eabi`` and the PyPI package ``unicorn`` (the ``mcu`` extra);
:func:`toolchain_missing` says which is absent.

Examples
--------
>>> missing = toolchain_missing()
>>> missing is None or "arm-none-eabi-gcc" in missing or "unicorn" in missing
True
"""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["CFLAGS", "ArmBuild", "EmulatedRun", "toolchain_missing", "build", "emulate", "host_run"]

#: The target's compiler flags (issue 34): Cortex-M4 with its single-precision FPU, hard-float ABI.
CFLAGS = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-O2")
_STRICT = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion", "-ffreestanding")

_TEXT = 0x0001_0000   # flash: the image
_RAM = 0x2000_0000    # RAM: stack, inputs, outputs
_STACK = 0x1_0000
_RETURN = 0x0000_1000  # the driver returns here: the emulation stops

_DRIVER = r"""
#include <stdint.h>
#include "obsdesign_controller.h"
/* Run n samples: in[2 i] = x_ref, in[2 i + 1] = x_meas [counts]; out[4 i ...] = command, v_hat, f_hat,
 * f_hat_filtered. */
void od_run(const int32_t *in, float *out, int32_t n) {
    obsdesign_controller c;
    int32_t i;
    obsdesign_controller_init(&c);
    for (i = 0; i < n; i++) {
        out[4 * i] = obsdesign_controller_step(&c, in[2 * i], in[2 * i + 1]);
        out[4 * i + 1] = c.v_hat;
        out[4 * i + 2] = c.f_hat;
        out[4 * i + 3] = c.f_hat_filtered;
    }
}
"""


@dataclass(frozen=True)
class ArmBuild:
    """The cross-compiled controller and its linked test image.

    Attributes
    ----------
    folder : Path
        Where the sources, objects and image are.
    flash, ram : int
        Bytes of the controller object: ``text + data`` (code and the constant table) and ``data + bss``
        (``arm-none-eabi-size``; the state lives in the caller's ``obsdesign_controller``).
    state : int
        ``sizeof(obsdesign_controller)`` [bytes].
    stack : int
        Largest stack frame of the step or one of its callees [bytes] (``-fstack-usage``).
    symbols : tuple of str
        The object's symbols (``arm-none-eabi-nm``).
    step_range : (int, int)
        Address range of the controller's code in the image (where instructions are counted).
    run_address : int
        Address of the driver ``od_run``.
    image : bytes
        The flat image, loaded at ``0x10000``.
    """

    folder: Path
    flash: int
    ram: int
    state: int
    stack: int
    symbols: tuple
    step_range: tuple
    run_address: int
    image: bytes


@dataclass(frozen=True)
class EmulatedRun:
    """One run of the step on the emulated Cortex-M4.

    Attributes
    ----------
    command, v_hat, f_hat, f_hat_filtered : ndarray
        Each sample's outputs (float32 values as float64).
    instructions : ndarray of int or None
        Instructions executed in the controller's code at each sample (None when not counted).
    """

    command: np.ndarray
    v_hat: np.ndarray
    f_hat: np.ndarray
    f_hat_filtered: np.ndarray
    instructions: np.ndarray | None


def toolchain_missing() -> str | None:
    """None when the cross compiler, its binutils and unicorn are available, else what is missing."""
    missing = [tool for tool in ("arm-none-eabi-gcc", "arm-none-eabi-nm", "arm-none-eabi-size", "arm-none-eabi-ld",
                                 "arm-none-eabi-objcopy") if shutil.which(tool) is None]
    try:
        import unicorn  # noqa: F401
    except ImportError:
        missing.append("unicorn (pip install unicorn)")
    return None if not missing else "missing " + ", ".join(missing) + " (Debian package gcc-arm-none-eabi)"


def _run(args, cwd) -> str:
    out = subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{args[0]} failed: {out.stderr.strip() or out.stdout.strip()}")
    return out.stdout


def build(files: dict[str, str], folder) -> ArmBuild:
    """Cross-compile the ``cortex-m4f`` controller files and link the test image.

    Parameters
    ----------
    files : dict of str to str
        ``obsdesign_controller.h`` and ``.c`` (:func:`obsdesign.export.mcu.mcu_controller_files`).
    folder : path
        A folder to work in (created if missing).

    Returns
    -------
    ArmBuild

    Raises
    ------
    RuntimeError
        The compiler refused the code, or the object needs an outside symbol (it must link alone:
        no ``__aeabi_d*`` soft-double helper, no libm or libc function).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)
    (folder / "od_driver.c").write_text(_DRIVER)
    gcc = ["arm-none-eabi-gcc", *_STRICT, *CFLAGS, "-I.", "-c"]
    _run([*gcc, "-fstack-usage", "obsdesign_controller.c", "-o", "obsdesign_controller.o"], folder)
    _run([*gcc, "od_driver.c", "-o", "od_driver.o"], folder)
    symbols = tuple(line.split()[-1] for line in _run(["arm-none-eabi-nm", "obsdesign_controller.o"], folder).splitlines()
                    if line.strip())
    undefined = _run(["arm-none-eabi-nm", "-u", "obsdesign_controller.o"], folder).split()
    undefined = [s for s in undefined if s != "U"]
    if undefined:
        raise RuntimeError(f"obsdesign_controller.o: expected no outside symbol (no __aeabi_d*, libm or libc), "
                           f"found {', '.join(undefined)}")
    text_bytes, data, bss = (int(v) for v in _run(["arm-none-eabi-size", "obsdesign_controller.o"], folder)
                       .splitlines()[1].split()[:3])
    stack = max(int(line.split()[-2]) for line in (folder / "obsdesign_controller.su").read_text().splitlines()
                if line.strip())
    # the controller's .text first, at _TEXT: its instructions are counted; the constant table after
    _run(["arm-none-eabi-ld", f"-Ttext=0x{_TEXT:x}", "-e", "od_run", "-o", "od_run.elf", "obsdesign_controller.o",
          "od_driver.o"], folder)
    _run(["arm-none-eabi-objcopy", "-O", "binary", "od_run.elf", "od_run.bin"], folder)
    table = {}
    for line in _run(["arm-none-eabi-nm", "od_run.elf"], folder).splitlines():
        parts = line.split()
        if len(parts) == 3:
            table[parts[2]] = int(parts[0], 16)
    sections = _run(["arm-none-eabi-size", "-A", "obsdesign_controller.o"], folder)
    code = int(re.search(r"^\.text\s+(\d+)", sections, re.M).group(1))
    state = _state_size(folder)
    return ArmBuild(folder=folder, flash=text_bytes + data, ram=data + bss, state=state, stack=stack, symbols=symbols,
                    step_range=(_TEXT, _TEXT + code), run_address=table["od_run"],
                    image=(folder / "od_run.bin").read_bytes())


def _state_size(folder: Path) -> int:
    """``sizeof(obsdesign_controller)`` for the target, read from a compiled constant."""
    (folder / "od_size.c").write_text('#include "obsdesign_controller.h"\n'
                                      "const unsigned od_state_size = sizeof(obsdesign_controller);\n")
    _run(["arm-none-eabi-gcc", *CFLAGS, "-I.", "-c", "od_size.c", "-o", "od_size.o"], folder)
    _run(["arm-none-eabi-objcopy", "-O", "binary", "-j", ".rodata", "od_size.o", "od_size.bin"], folder)
    return int.from_bytes((folder / "od_size.bin").read_bytes()[:4], "little")


def _thumb_count(code: bytes) -> int:
    """Instructions in a run of Thumb-2 code: a halfword 0b11101/0b11110/0b11111 starts a 32-bit one."""
    n = i = 0
    while i + 1 < len(code):
        half = code[i] | (code[i + 1] << 8)
        i += 4 if (half >> 11) in (0b11101, 0b11110, 0b11111) else 2
        n += 1
    return n


def emulate(arm: ArmBuild, x_ref, x_meas, *, count: bool = True) -> EmulatedRun:
    """Run the controller's step on the emulated Cortex-M4 over a sequence of samples.

    Parameters
    ----------
    arm : ArmBuild
        From :func:`build`.
    x_ref, x_meas : array_like of int
        Set-point and measurement of each sample [counts] (int32).
    count : bool
        Count the instructions of each step (a hook on every executed block; about 30x slower).

    Returns
    -------
    EmulatedRun
    """
    from unicorn import UC_ARCH_ARM, UC_HOOK_BLOCK, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
    from unicorn import arm_const as arm_reg

    x_ref = np.asarray(x_ref, dtype=np.int32)
    x_meas = np.asarray(x_meas, dtype=np.int32)
    if x_ref.shape != x_meas.shape or x_ref.ndim != 1:
        raise ValueError(f"x_ref, x_meas: expected two 1-d sequences of one length, found shapes "
                         f"{x_ref.shape} and {x_meas.shape}")
    n = x_ref.shape[0]
    uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
    uc.ctl_set_cpu_model(arm_reg.UC_CPU_ARM_CORTEX_M4)
    page = 0x1000
    uc.mem_map(0, page)  # the return address
    image_size = (len(arm.image) + page - 1) // page * page
    uc.mem_map(_TEXT, image_size)
    uc.mem_write(_TEXT, arm.image)
    inputs = np.column_stack([x_ref, x_meas]).astype("<i4").tobytes()
    in_at = _RAM + _STACK
    out_at = in_at + (len(inputs) + page - 1) // page * page
    total = out_at + (16 * n + page - 1) // page * page - _RAM
    uc.mem_map(_RAM, total)
    uc.mem_write(in_at, inputs)
    # FPU on: CPACR full access to CP10 and CP11
    uc.reg_write(arm_reg.UC_ARM_REG_C1_C0_2, uc.reg_read(arm_reg.UC_ARM_REG_C1_C0_2) | (0xF << 20))
    uc.reg_write(arm_reg.UC_ARM_REG_FPEXC, 0x40000000)
    uc.reg_write(arm_reg.UC_ARM_REG_SP, _RAM + _STACK - 16)
    uc.reg_write(arm_reg.UC_ARM_REG_R0, in_at)
    uc.reg_write(arm_reg.UC_ARM_REG_R1, out_at)
    uc.reg_write(arm_reg.UC_ARM_REG_R2, n)
    uc.reg_write(arm_reg.UC_ARM_REG_LR, _RETURN | 1)
    counts: list[int] = []
    if count:
        lo, hi = arm.step_range
        step_entry = _step_entry(arm)
        sizes: dict[tuple, int] = {}

        def on_block(emu, address, size, _):
            key = (address, size)
            c = sizes.get(key)
            if c is None:
                c = sizes[key] = _thumb_count(bytes(emu.mem_read(address, size)))
            if address == step_entry:
                counts.append(c)
            elif counts:  # (obsdesign_controller_init runs before the first step: not counted)
                counts[-1] += c

        uc.hook_add(UC_HOOK_BLOCK, on_block, begin=lo, end=hi - 1)
    uc.emu_start(arm.run_address | 1, _RETURN)
    out = np.frombuffer(bytes(uc.mem_read(out_at, 16 * n)), dtype="<f4").reshape(n, 4).astype(float)
    instructions = np.array(counts, dtype=np.int64) if count else None
    if count and len(counts) != n:
        raise RuntimeError(f"instruction count: expected {n} steps, found {len(counts)}")
    return EmulatedRun(command=out[:, 0], v_hat=out[:, 1], f_hat=out[:, 2], f_hat_filtered=out[:, 3],
                       instructions=instructions)


def _step_entry(arm: ArmBuild) -> int:
    for line in _run(["arm-none-eabi-nm", "od_run.elf"], arm.folder).splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == "obsdesign_controller_step":
            return int(parts[0], 16) & ~1
    raise RuntimeError("od_run.elf: expected the symbol obsdesign_controller_step, found none")


_HOST_DRIVER = r"""
#include <stdio.h>
#include "obsdesign_controller.h"
/* stdin: pairs of doubles (x_ref, x_meas); stdout: command, v_hat, f_hat, f_hat_filtered as doubles. */
int main(void) {
    double in[2], out[4];
    obsdesign_controller c;
    obsdesign_controller_init(&c);
    while (fread(in, sizeof in, 1, stdin) == 1) {
        out[0] = obsdesign_controller_step(&c, in[0], in[1]);
        out[1] = c.v_hat;
        out[2] = c.f_hat;
        out[3] = c.f_hat_filtered;
        fwrite(out, sizeof out, 1, stdout);
    }
    return 0;
}
"""


def host_run(files: dict[str, str], x_ref, x_meas, folder) -> EmulatedRun:
    """Run the ``host`` C controller (double, bit-exact with simulate) compiled by ``gcc`` on this machine.

    The double reference of :func:`emulate`: the same inputs in metres (``counts * resolution``).

    Parameters
    ----------
    files : dict of str to str
        ``obsdesign_controller.h`` and ``.c`` of the host target.
    x_ref, x_meas : array_like of float
        Set-point and measurement of each sample [m].
    folder : path
        A folder to work in (created if missing).

    Returns
    -------
    EmulatedRun
        Without instruction counts.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)
    (folder / "od_host.c").write_text(_HOST_DRIVER)
    _run(["gcc", "-std=c99", "-O2", "-I.", "-o", "od_host", "od_host.c", "obsdesign_controller.c", "-lm"], folder)
    data = np.column_stack([np.asarray(x_ref, float), np.asarray(x_meas, float)]).astype("<f8").tobytes()
    out = subprocess.run([str(folder / "od_host")], input=data, capture_output=True, check=True).stdout
    table = np.frombuffer(out, dtype="<f8").reshape(-1, 4)
    return EmulatedRun(command=table[:, 0].copy(), v_hat=table[:, 1].copy(), f_hat=table[:, 2].copy(),
                       f_hat_filtered=table[:, 3].copy(), instructions=None)

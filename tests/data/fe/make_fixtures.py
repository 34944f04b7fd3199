"""Write the FE-export fixtures of this folder: one cantilever in every format mmshbm reads.

    python tests/data/fe/make_fixtures.py [OUTPUT_FOLDER]     # default: this folder

The structure: a clamped-free Euler–Bernoulli beam (``mmshbm.fe.euler_bernoulli``), the
default beam's section (0.5 m x 20 mm x 13.5 mm, steel), 10 equal elements, consistent
mass on every node. Nodes 1..11 from the root, node 1 clamped; each free node has the
deflection u_y (component 2) and the rotation r_z (component 6): 20 DOFs, the tip is node
11. Each file is written by its format's own rules (no package writes them here except
scipy's Matrix Market / Harwell–Boeing / MATLAB v5 writers and h5py for v7.3):

==========================  ==========================================================
beam_MASS1.mtx, beam_STIF1.mtx  Abaqus *MATRIX OUTPUT, FORMAT=MATRIX INPUT (lower triangle)
beam_substructure.inp       Abaqus *USER ELEMENT, LINEAR with *MATRIX (upper triangle by columns)
beam.op4                    NASTRAN OUTPUT4 text, dense columns (KAA, MAA)
beam_sparse.op4             NASTRAN OUTPUT4 text, sparse (string headers IS)
beam_binary.op4             NASTRAN OUTPUT4 binary little-endian, dense, double
beam_bigmat.op4             NASTRAN OUTPUT4 binary big-endian, sparse BIGMAT, double
beam.pch                    NASTRAN DMIG punch cards, large field (KAAX, MAAX; IFO 6)
beam_M.mtx, beam_K.mtx      Matrix Market (symmetric, coordinate)
beam_M.rua, beam_K.rua      Harwell–Boeing (scipy.io.hb_write)
beam.mat                    MATLAB v5 (M, K, dofs)
beam_v73.mat                MATLAB v7.3 (HDF5, sparse groups data/ir/jc) if h5py is installed
beam_aster.npz              code_aster EXTR_MATR(sparse=True) triplets with the root fixed by
                            double Lagrange multipliers (AFFE_CHAR_MECA DDL_IMPO)
beam.npz                    mmshbm's own layout (Model.save_npz), contact at the tip
==========================  ==========================================================
"""

from __future__ import annotations

import struct
import sys
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2]))

N_ELEMENTS = 10
GEOMETRY = dict(length=0.5, width=0.020, height=0.0135, E=210e9, rho=7850.0)
TIP_NODE = N_ELEMENTS + 1
#: (node, component) of the rows of M and K: u_y (2) and r_z (6) of nodes 2..11
DOFS = np.array([(node, comp) for node in range(2, N_ELEMENTS + 2) for comp in (2, 6)])


def cantilever():
    """(M, K) dense, 20 x 20, rows as :data:`DOFS`."""
    from mmshbm.fe.euler_bernoulli import cantilever as eb

    M, K, _ = eb(GEOMETRY["length"], GEOMETRY["width"], GEOMETRY["height"], GEOMETRY["E"], GEOMETRY["rho"],
                 N_ELEMENTS)
    return M.toarray(), K.toarray()


def full_cantilever():
    """(M, K) dense, 22 x 22, the root node's DOFs first (unconstrained)."""
    from mmshbm.fe import assembly
    from mmshbm.fe.euler_bernoulli import element_matrices

    g = GEOMETRY
    Ke, Me = element_matrices(np.full(N_ELEMENTS, g["length"] / N_ELEMENTS), g["E"],
                              g["width"] * g["height"] ** 3 / 12.0, g["rho"], g["width"] * g["height"])
    chain = assembly.chain_dofs(N_ELEMENTS)
    return assembly.assemble(Me, chain).toarray(), assembly.assemble(Ke, chain).toarray()


# ---------------------------------------------------------------------- Abaqus
def abaqus_matrix_input(path: Path, A: np.ndarray) -> None:
    lines = [f"{DOFS[i, 0]},{DOFS[i, 1]}, {DOFS[j, 0]},{DOFS[j, 1]}, {A[i, j]:.16e}\n"
             for i in range(len(A)) for j in range(i + 1) if A[i, j] != 0.0]
    path.write_text("".join(lines))


def abaqus_user_element(path: Path, M: np.ndarray, K: np.ndarray) -> None:
    nodes = list(range(2, N_ELEMENTS + 2))
    out = ["** substructure of the 10-element cantilever (nodes 2..11; node 1 clamped)\n",
           f"*USER ELEMENT, NODES={len(nodes)}, TYPE=U1, LINEAR\n", "2, 6\n",
           "*ELEMENT, TYPE=U1, ELSET=CANTILEVER\n", "1, " + ", ".join(map(str, nodes)) + "\n"]
    for kind, A in (("STIFFNESS", K), ("MASS", M)):
        out.append(f"*MATRIX, TYPE={kind}\n")
        packed = [A[i, j] for j in range(len(A)) for i in range(j + 1)]  # upper triangle by columns
        for k in range(0, len(packed), 4):
            out.append(", ".join(f"{v:.16e}" for v in packed[k:k + 4]) + "\n")
    path.write_text("".join(out))


# ---------------------------------------------------------------------- NASTRAN OP4
def op4_text(path: Path, matrices: dict, sparse: bool) -> None:
    out = []
    for name, A in matrices.items():
        n = len(A)
        out.append(f"{n:8d}{n:8d}{6:8d}{2:8d}{name:<8s}1P,3E23.16\n")
        for j in range(n):
            col = A[:, j]
            nz = np.flatnonzero(col)
            if not len(nz):
                continue
            if sparse:
                strings = _strings(nz)
                words = sum(1 + 2 * (b - a + 1) for a, b in strings)
                out.append(f"{j + 1:8d}{0:8d}{words:8d}\n")
                for a, b in strings:
                    out.append(f"{(a + 1) + 65536 * (2 * (b - a + 1) + 1):12d}\n")
                    out += _values(col[a:b + 1])
            else:
                a, b = nz[0], nz[-1]
                out.append(f"{j + 1:8d}{a + 1:8d}{2 * (b - a + 1):8d}\n")
                out += _values(col[a:b + 1])
        out.append(f"{n + 1:8d}{1:8d}{2:8d}\n")
        out += _values(np.array([1.0]))
    path.write_text("".join(out))


def _strings(nz):
    """Runs of consecutive row indices: [(first, last)]."""
    runs, start = [], nz[0]
    for a, b in zip(nz, list(nz[1:]) + [None], strict=True):
        if b != a + 1:
            runs.append((start, a))
            start = b
    return runs


def _values(v):
    return ["".join(f"{x:23.16E}" for x in v[k:k + 3]) + "\n" for k in range(0, len(v), 3)]


def op4_binary(path: Path, matrices: dict, endian: str, bigmat: bool) -> None:
    def record(fmt, *values):
        body = struct.pack(endian + fmt, *values)
        return struct.pack(endian + "i", len(body)) + body + struct.pack(endian + "i", len(body))

    out = b""
    for name, A in matrices.items():
        n = len(A)
        out += struct.pack(endian + "i", 24) + struct.pack(endian + "4i", n, -n if bigmat else n, 6, 2) + \
            name.ljust(8).encode() + struct.pack(endian + "i", 24)
        for j in range(n):
            col = A[:, j]
            nz = np.flatnonzero(col)
            if not len(nz):
                continue
            if bigmat:
                body = b""
                for a, b in _strings(nz):
                    nwords = 2 * (b - a + 1)
                    body += struct.pack(endian + "2i", nwords + 1, a + 1) + \
                        struct.pack(f"{endian}{b - a + 1}d", *col[a:b + 1])
                head = struct.pack(endian + "3i", j + 1, 0, len(body) // 4)
                out += struct.pack(endian + "i", len(head + body)) + head + body + \
                    struct.pack(endian + "i", len(head + body))
            else:
                a, b = nz[0], nz[-1]
                out += record(f"3i{b - a + 1}d", j + 1, a + 1, 2 * (b - a + 1), *col[a:b + 1])
        out += record("3id", n + 1, 1, 2, 1.0)
    path.write_bytes(out)


# ---------------------------------------------------------------------- NASTRAN DMIG
def dmig_large(path: Path, matrices: dict) -> None:
    def f16(v):
        return f"{v:16.9E}".replace("E", "D")

    out = ["$ DMIG punch of the 10-element cantilever (IFO 6: upper triangle by columns)\n"]
    for name, A in matrices.items():
        out.append(f"{'DMIG':8s}{name:8s}{'0':>8s}{'6':>8s}{'2':>8s}{'0':>8s}{'':8s}{'':8s}{len(A):8d}\n")
        for j in range(len(A)):
            out.append(f"{'DMIG*':8s}{name:16s}{DOFS[j, 0]:16d}{DOFS[j, 1]:16d}\n")
            for i in range(j + 1):
                if A[i, j] != 0.0:
                    out.append(f"{'*':8s}{DOFS[i, 0]:16d}{DOFS[i, 1]:16d}{f16(A[i, j])}\n")
    path.write_text("".join(out))


# ---------------------------------------------------------------------- MATLAB v7.3
def matlab_v73(path: Path, M: np.ndarray, K: np.ndarray) -> bool:
    try:
        import h5py
    except ImportError:
        return False
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, A in (("M", M), ("K", K)):
            S = sp.csc_matrix(A)
            g = f.create_group(name)
            g.attrs["MATLAB_class"] = np.bytes_("double")
            g.attrs["MATLAB_sparse"] = np.uint64(S.shape[0])
            g.create_dataset("data", data=S.data)
            g.create_dataset("ir", data=S.indices.astype(np.uint64))
            g.create_dataset("jc", data=S.indptr.astype(np.uint64))
        d = f.create_dataset("dofs", data=DOFS.T.astype(float))  # MATLAB stores columns first
        d.attrs["MATLAB_class"] = np.bytes_("double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: mmshbm fixtures HDF5 schema 1.00 ."
    with open(path, "r+b") as f:
        f.write(header.ljust(116) + b"\x00" * 8 + struct.pack("<H", 0x0200) + b"IM" + b"\x00" * (512 - 128))
    return True


# ---------------------------------------------------------------------- code_aster
def code_aster(path: Path) -> None:
    """Double Lagrange multipliers on the root node's u_y and r_z, as AFFE_CHAR_MECA(DDL_IMPO)
    dualises them: [[K, b, b], [b, -a, a], [b, a, -a]] per fixed DOF (upper triangle stored)."""
    M, K = full_cantilever()
    n = len(K)
    fixed = [0, 1]
    m = n + 2 * len(fixed)
    Ka, Ma = np.zeros((m, m)), np.zeros((m, m))
    Ka[:n, :n], Ma[:n, :n] = K, M
    alpha = float(np.max(np.abs(K)))
    for k, dof in enumerate(fixed):
        l1, l2 = n + 2 * k, n + 2 * k + 1
        Ka[dof, l1] = Ka[l1, dof] = Ka[dof, l2] = Ka[l2, dof] = alpha
        Ka[l1, l1] = Ka[l2, l2] = -alpha
        Ka[l1, l2] = Ka[l2, l1] = alpha
    nodes = [1, 1] + [int(v) for v in DOFS[:, 0]] + [1, 1, 1, 1]
    components = ["DY", "DRZ"] + ["DY" if c == 2 else "DRZ" for c in DOFS[:, 1]] + ["LAGR:DY"] * 2 + \
        ["LAGR:DRZ"] * 2
    parts = {}
    for role, A in (("K", Ka), ("M", Ma)):
        U = sp.triu(sp.coo_matrix(A)).tocoo()
        parts.update({f"{role}_data": U.data, f"{role}_rows": U.row, f"{role}_cols": U.col})
    np.savez(path, **parts, dim=m, nodes=np.array(nodes), components=np.array(components))


def main(out: Path = HERE) -> None:
    """Write every fixture into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    from mmshbm.model.model import Model

    M, K = cantilever()
    abaqus_matrix_input(out / "beam_MASS1.mtx", M)
    abaqus_matrix_input(out / "beam_STIF1.mtx", K)
    abaqus_user_element(out / "beam_substructure.inp", M, K)
    op4_text(out / "beam.op4", {"KAA": K, "MAA": M}, sparse=False)
    op4_text(out / "beam_sparse.op4", {"KAA": K, "MAA": M}, sparse=True)
    op4_binary(out / "beam_binary.op4", {"KAA": K, "MAA": M}, "<", bigmat=False)
    op4_binary(out / "beam_bigmat.op4", {"KAA": K, "MAA": M}, ">", bigmat=True)
    dmig_large(out / "beam.pch", {"KAAX": K, "MAAX": M})
    for name, A in (("M", M), ("K", K)):
        scipy.io.mmwrite(str(out / f"beam_{name}.mtx"), sp.coo_matrix(A), symmetry="symmetric",
                         precision=17)
        scipy.io.hb_write(str(out / f"beam_{name}.rua"), sp.csc_matrix(A))
    scipy.io.savemat(str(out / "beam.mat"), {"M": sp.csc_matrix(M), "K": sp.csc_matrix(K),
                                              "dofs": DOFS.astype(float)})
    matlab_v73(out / "beam_v73.mat", M, K)
    code_aster(out / "beam_aster.npz")
    tip = int(np.flatnonzero((DOFS[:, 0] == TIP_NODE) & (DOFS[:, 1] == 2))[0])
    Model.from_matrices(M, K, tip, 1e-3).save_npz(out / "beam.npz")


if __name__ == "__main__":
    main(*sys.argv[1:2])

"""Opens XDMF files with each of ParaView's XDMF readers and checks them.

Run with pvpython (Debian's paraview package): for each file and each reader
(XDMFReader, Xdmf3ReaderS, Xdmf3ReaderT), it reads the last time step and
checks that:
- the reader sees as many time steps as the file has <Time> values per grid;
- every grid has cells (vertex cells for the particles, one per sphere);
- the expected point arrays are there together on one grid, as 64-bit
  floats (the shell's displacement and velocity, the particles' radius,
  displacement, velocity and damage); a shell's grid also carries its
  section's cell arrays (stresses, forces, moments: 9 components each).

Usage: pvpython paraview_check.py FILE.xdmf ...
Prints a line per file and reader; exits 1 on any problem.
"""
import re
import sys

from paraview import servermanager
from paraview.simple import Delete, XDMFReader, Xdmf3ReaderS, Xdmf3ReaderT

EXPECTED = {
    "particles": {"radius", "displacement", "velocity", "damage"},
    "shell": {"displacement", "velocity"},
}
CELL_EXPECTED = {
    "particles": set(),
    "shell": {"stress_top", "stress_bottom", "membrane_force", "bending_moment"},
}


def leaves(data):
    """The datasets inside a (possibly nested) composite dataset."""
    if data is None:
        return []
    if data.IsA("vtkCompositeDataSet"):
        out = []
        it = data.NewIterator()
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            out.append(it.GetCurrentDataObject())
            it.GoToNextItem()
        return out
    return [data]


def check(path, make, name):
    problems = []
    text = open(path).read()
    times = sorted({float(t) for t in re.findall(r'<Time Value="([^"]+)"', text)})
    grid = "particles" if "Polyvertex" in text else "shell"
    reader = make(path)
    reader.UpdatePipelineInformation()
    steps = list(getattr(reader, "TimestepValues", []) or [])
    if len(times) > 1 and len(steps) != len(times):
        problems.append(f"{len(steps)} time steps seen, the file has {len(times)}")
    reader.UpdatePipeline(times[-1] if times else 0.0)
    data = servermanager.Fetch(reader)
    found = False
    for d in leaves(data):
        if d is None or not d.IsA("vtkDataSet") or d.GetNumberOfPoints() == 0:
            continue
        names = {d.GetPointData().GetArrayName(i) for i in range(d.GetPointData().GetNumberOfArrays())}
        if not EXPECTED[grid] <= names:
            continue
        found = True
        if d.GetNumberOfCells() == 0:
            problems.append(f"{d.GetNumberOfPoints()} points but no cell")
        if grid == "particles" and d.GetNumberOfCells() != d.GetNumberOfPoints():
            problems.append(f"{d.GetNumberOfCells()} cells for {d.GetNumberOfPoints()} particles")
        for a in EXPECTED[grid]:
            arr = d.GetPointData().GetArray(a)
            if arr.GetDataTypeAsString() != "double":
                problems.append(f"array {a} is {arr.GetDataTypeAsString()}, not double")
        cells = {d.GetCellData().GetArrayName(i) for i in range(d.GetCellData().GetNumberOfArrays())}
        # shells (triangles, quadrilaterals) carry their section's tensors;
        # bars (polylines) and solids do not
        shells = re.search(r'TopologyType="(Triangle|Quadrilateral)"', text) is not None
        for a in CELL_EXPECTED[grid] if shells else ():
            arr = d.GetCellData().GetArray(a)
            if arr is None:
                problems.append(f"no cell array {a}")
            elif arr.GetNumberOfComponents() != 9 or arr.GetNumberOfTuples() != d.GetNumberOfCells():
                problems.append(f"cell array {a}: {arr.GetNumberOfComponents()} components, "
                                f"{arr.GetNumberOfTuples()} tuples for {d.GetNumberOfCells()} cells")
        print(f"{path}: {name}: {len(steps)} steps, {d.GetNumberOfPoints()} points, "
              f"{d.GetNumberOfCells()} cells, arrays {sorted(names)}, cell arrays {sorted(cells)}")
    if not found:
        problems.append(f"no grid with the arrays {sorted(EXPECTED[grid])} together")
    Delete(reader)
    return [f"{path}: {name}: {p}" for p in problems]


def main(files):
    readers = [("XDMFReader", lambda f: XDMFReader(FileNames=[f])),
               ("Xdmf3ReaderS", lambda f: Xdmf3ReaderS(FileName=[f])),
               ("Xdmf3ReaderT", lambda f: Xdmf3ReaderT(FileName=[f]))]
    problems = []
    for f in files:
        for name, make in readers:
            try:
                problems += check(f, make, name)
            except Exception as e:  # noqa: BLE001 -- a reader that fails is the finding
                problems.append(f"{f}: {name}: {e}")
    for p in problems:
        print(p)
    print(f"{len(files)} files, {len(problems)} problems")
    return 1 if problems or not files else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

# Opens the results.xdmf of a patient-on-array run with each of ParaView's XDMF readers and
# checks its three parts at the first and the last time: the mat (a layer of cells under the bed
# board; its pressure is read by the XDMF 2 reader, which must see some at the last time), the
# bags and the body (triangle meshes with the points and triangles results.xdmf states), and
# that the body moved between the two. Run with pvpython:
#   pvpython CheckArrayXdmfParaView.py OUT/results.xdmf
import os
import sys
import xml.etree.ElementTree as ET

from paraview import servermanager as sm
from paraview import simple

path = os.path.abspath(sys.argv[1])
root = ET.parse(path).getroot()
expected = {}
for coll in root.findall("./Domain/Grid"):
    name = coll.get("Name")
    grids = coll.findall("./Grid")
    topo = grids[0].find("Topology")
    if topo.get("TopologyType") == "Triangle":
        cells = int(topo.get("NumberOfElements"))
        points = int(grids[0].find("Geometry/DataItem").get("Dimensions").split()[0])
    else:
        dims = [int(v) for v in topo.get("Dimensions").split()]  # points per axis
        cells, points = 1, 1
        for d in dims:
            cells, points = cells * max(d - 1, 1), points * d
    expected[name] = (points, cells, len(grids))
print("results.xdmf:", expected)
if set(expected) != {"pressure mat", "bags", "body"}:
    print("expected the collections pressure mat, bags and body")
    sys.exit(1)


def blocks(data):
    """The leaf datasets of a multiblock, in order."""
    out = []
    if data.IsA("vtkCompositeDataSet"):
        it = data.NewIterator()
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            out.append(it.GetCurrentDataObject())
            it.GoToNextItem()
    else:
        out.append(data)
    return out


failures = []
for name in ["Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader"]:
    if name == "XDMFReader":
        reader = simple.XDMFReader(FileNames=[path])
    else:
        reader = getattr(simple, name)(FileName=[path])
    times = list(reader.TimestepValues)
    bodies = []
    for t in [times[0], times[-1]]:
        reader.UpdatePipeline(t)
        got = [(b.GetNumberOfPoints(), b.GetNumberOfCells()) for b in blocks(sm.Fetch(reader))]
        want = [expected[k][:2] for k in ["pressure mat", "bags", "body"]]
        if sorted(got) != sorted(want):
            failures.append("%s at t=%g: blocks %s, expected %s" % (name, t, got, want))
            break
        body = [b for b in blocks(sm.Fetch(reader)) if b.GetNumberOfPoints() == want[2][0]][0]
        if name == "XDMFReader" and t == times[-1]:
            # The mat's pressure (a hyperslab of /mat/pressure: the Xdmf3 readers skip it).
            mat = [b for b in blocks(sm.Fetch(reader)) if b.GetNumberOfPoints() == want[0][0]][0]
            p = mat.GetCellData().GetArray("pressure_Pa")
            if p is None or not p.GetRange()[1] > 0.0:
                failures.append("XDMFReader: no mat pressure above 0 at the last time")
            else:
                print("XDMFReader: mat pressure up to %.4g Pa at the last time" % p.GetRange()[1])
        bodies.append([body.GetPoint(i) for i in range(body.GetNumberOfPoints())])
    if len(bodies) == 2:
        moved = max(abs(a[k] - b[k]) for a, b in zip(*bodies) for k in range(3))
        print("%s: %d time steps; mat, bags, body %s; largest body node travel %.4g m" %
              (name, len(times), want, moved))
        if not moved > 0.0:
            failures.append("%s: the body did not move from the first to the last time" % name)

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("ParaView reads %s (mat, bags, body) with all three XDMF readers" % path)

#include "Hdf5.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace io::h5 {

void Handle::reset() {
    if (m_id < 0) return;
    switch (H5Iget_type(m_id)) {
        case H5I_FILE:
            H5Fclose(m_id);
            break;
        case H5I_GROUP:
            H5Gclose(m_id);
            break;
        case H5I_DATASET:
            H5Dclose(m_id);
            break;
        case H5I_DATASPACE:
            H5Sclose(m_id);
            break;
        case H5I_DATATYPE:
            H5Tclose(m_id);
            break;
        case H5I_ATTR:
            H5Aclose(m_id);
            break;
        case H5I_GENPROP_LST:
            H5Pclose(m_id);
            break;
        default:
            break;
    }
    m_id = H5I_INVALID_HID;
}

void silenceErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

hid_t check(hid_t status, const std::string& what) {
    if (status < 0) throw std::runtime_error("HDF5: " + what);
    return status;
}

Handle createFile(const std::string& path) {
    silenceErrors();
    return Handle(check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                        "cannot create " + path));
}

Handle createGroup(hid_t loc, const std::string& name) {
    return Handle(check(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                        "cannot create group " + name));
}

namespace {

// Replaces an attribute: HDF5 attributes cannot change type or size once written.
void removeAttribute(hid_t obj, const std::string& name) {
    if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
}

Handle makeStringType(size_t length) {
    Handle type(check(H5Tcopy(H5T_C_S1), "string type"));
    check(H5Tset_size(type.get(), length > 0 ? length : 1), "string size");
    check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), "string padding");
    check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
    return type;
}

void writeAttribute(hid_t obj, const std::string& name, hid_t fileType, hid_t memType,
                    const std::vector<hsize_t>& dims, const void* data) {
    removeAttribute(obj, name);
    Handle space(dims.empty()
                     ? check(H5Screate(H5S_SCALAR), "dataspace")
                     : check(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                             "dataspace"));
    Handle attr(
        check(H5Acreate2(obj, name.c_str(), fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              "cannot create attribute " + name));
    check(H5Awrite(attr.get(), memType, data), "cannot write attribute " + name);
}

}  // namespace

void setAttribute(hid_t obj, const std::string& name, const std::string& value) {
    Handle type = makeStringType(value.size());
    writeAttribute(obj, name, type.get(), type.get(), {}, value.data());
}

void setAttribute(hid_t obj, const std::string& name, double value) {
    writeAttribute(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &value);
}

void setAttribute(hid_t obj, const std::string& name, int value) {
    writeAttribute(obj, name, H5T_STD_I32LE, H5T_NATIVE_INT, {}, &value);
}

void setAttribute(hid_t obj, const std::string& name, const std::vector<std::string>& values) {
    size_t len = 1;
    for (const std::string& v : values) len = std::max(len, v.size());
    std::vector<char> buf(len * std::max<size_t>(values.size(), 1), '\0');
    for (size_t i = 0; i < values.size(); ++i) values[i].copy(buf.data() + i * len, len);
    Handle type = makeStringType(len);
    writeAttribute(obj, name, type.get(), type.get(), {std::max<hsize_t>(values.size(), 1)},
                   buf.data());
}

void setAttribute(hid_t obj, const std::string& name, const std::vector<double>& values) {
    const double zero = 0.0;
    writeAttribute(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                   {std::max<hsize_t>(values.size(), 1)}, values.empty() ? &zero : values.data());
}

namespace {

void writeWhole(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                hid_t fileType, hid_t memType, const void* data, const std::string& unit) {
    Handle space(check(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                       "dataspace of " + name));
    Handle ds(check(
        H5Dcreate2(loc, name.c_str(), fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
        "cannot create dataset " + name));
    hsize_t total = 1;
    for (hsize_t d : dims) total *= d;
    if (total > 0)
        check(H5Dwrite(ds.get(), memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
              "cannot write dataset " + name);
    if (!unit.empty()) setAttribute(ds.get(), "unit", unit);
}

}  // namespace

void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const double* data, const std::string& unit) {
    writeWhole(loc, name, dims, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data, unit);
}

void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const int* data, const std::string& unit) {
    writeWhole(loc, name, dims, H5T_STD_I32LE, H5T_NATIVE_INT, data, unit);
}

void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const float* data, const std::string& unit) {
    writeWhole(loc, name, dims, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, data, unit);
}

GrowingDataset::GrowingDataset(hid_t loc, const std::string& name, hid_t type,
                               std::vector<hsize_t> inner, hsize_t chunkRows,
                               const std::string& unit)
    : m_type(type), m_inner(std::move(inner)), m_name(name) {
    const int rank = 1 + static_cast<int>(m_inner.size());
    std::vector<hsize_t> dims(rank, 0), maxDims(rank, H5S_UNLIMITED), chunk(rank, 1);
    chunk[0] = chunkRows > 0 ? chunkRows : 1;
    for (size_t i = 0; i < m_inner.size(); ++i) {
        // An empty inner axis stays unlimited: a chunk may not exceed a fixed maximum.
        dims[i + 1] = m_inner[i];
        maxDims[i + 1] = m_inner[i] > 0 ? m_inner[i] : H5S_UNLIMITED;
        chunk[i + 1] = std::max<hsize_t>(m_inner[i], 1);
    }
    Handle space(
        check(H5Screate_simple(rank, dims.data(), maxDims.data()), "dataspace of " + name));
    Handle plist(check(H5Pcreate(H5P_DATASET_CREATE), "property list"));
    check(H5Pset_chunk(plist.get(), rank, chunk.data()), "chunking of " + name);
    hid_t fileType = type == H5T_NATIVE_DOUBLE ? H5T_IEEE_F64LE
                     : type == H5T_NATIVE_INT8 ? H5T_STD_I8LE
                                               : H5T_STD_I32LE;
    m_dataset = Handle(check(
        H5Dcreate2(loc, name.c_str(), fileType, space.get(), H5P_DEFAULT, plist.get(), H5P_DEFAULT),
        "cannot create dataset " + name));
    if (!unit.empty()) setAttribute(m_dataset.get(), "unit", unit);
}

void GrowingDataset::append(const void* data, hsize_t rows) {
    if (rows == 0) return;
    const int rank = 1 + static_cast<int>(m_inner.size());
    std::vector<hsize_t> dims(rank), start(rank, 0), count(rank);
    dims[0] = m_rows + rows;
    count[0] = rows;
    start[0] = m_rows;
    for (size_t i = 0; i < m_inner.size(); ++i) dims[i + 1] = count[i + 1] = m_inner[i];
    check(H5Dset_extent(m_dataset.get(), dims.data()), "cannot extend " + m_name);
    Handle fileSpace(check(H5Dget_space(m_dataset.get()), "dataspace of " + m_name));
    check(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                              nullptr),
          "selection in " + m_name);
    Handle memSpace(check(H5Screate_simple(rank, count.data(), nullptr), "memory space"));
    check(H5Dwrite(m_dataset.get(), m_type, memSpace.get(), fileSpace.get(), H5P_DEFAULT, data),
          "cannot write " + m_name);
    m_rows += rows;
}

GrowingDataset GrowingDataset::open(hid_t loc, const std::string& name, hid_t type,
                                    std::vector<hsize_t> inner, hsize_t rows) {
    GrowingDataset d;
    d.m_type = type;
    d.m_inner = std::move(inner);
    d.m_name = name;
    d.m_dataset = Handle(check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), "cannot open " + name));
    const int rank = 1 + static_cast<int>(d.m_inner.size());
    Handle space(check(H5Dget_space(d.m_dataset.get()), "dataspace of " + name));
    if (H5Sget_simple_extent_ndims(space.get()) != rank)
        throw std::runtime_error("HDF5: " + name + " has another shape than expected");
    std::vector<hsize_t> dims(rank);
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    if (dims[0] < rows)
        throw std::runtime_error("HDF5: " + name + " has " + std::to_string(dims[0]) +
                                 " rows, fewer than the " + std::to_string(rows) + " to keep");
    dims[0] = rows;
    check(H5Dset_extent(d.m_dataset.get(), dims.data()), "cannot cut back " + name);
    d.m_rows = rows;
    return d;
}

Handle openFileReadWrite(const std::string& path) {
    silenceErrors();
    if (H5Fis_hdf5(path.c_str()) <= 0)
        throw std::runtime_error("not an HDF5 file (or it cannot be read)");
    return Handle(check(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT),
                        "cannot open it to write (is a run still writing it?)"));
}

void deleteLink(hid_t loc, const std::string& name) {
    check(H5Ldelete(loc, name.c_str(), H5P_DEFAULT), "cannot remove " + name);
}

Handle openFileReadOnly(const std::string& path) {
    silenceErrors();
    if (H5Fis_hdf5(path.c_str()) <= 0)
        throw std::runtime_error("not an HDF5 file (or it cannot be read)");
    return Handle(check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                        "cannot open it (is a run still writing it?)"));
}

bool hasLink(hid_t loc, const std::string& name) {
    return H5Lexists(loc, name.c_str(), H5P_DEFAULT) > 0;
}

Handle openGroup(hid_t loc, const std::string& name) {
    return Handle(check(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), "cannot open group " + name));
}

bool hasAttribute(hid_t obj, const std::string& name) { return H5Aexists(obj, name.c_str()) > 0; }

std::string readStringAttribute(hid_t obj, const std::string& name) {
    Handle attr(check(H5Aopen(obj, name.c_str(), H5P_DEFAULT), "cannot open attribute " + name));
    Handle type(check(H5Aget_type(attr.get()), "type of attribute " + name));
    if (H5Tget_class(type.get()) != H5T_STRING)
        throw std::runtime_error("HDF5: attribute " + name + " is not a string");
    Handle space(check(H5Aget_space(attr.get()), "dataspace of attribute " + name));
    const hssize_t n = std::max<hssize_t>(H5Sget_simple_extent_npoints(space.get()), 1);
    std::string out;
    if (H5Tis_variable_str(type.get()) > 0) {
        std::vector<char*> v(n, nullptr);
        Handle mem(check(H5Tcopy(H5T_C_S1), "string type"));
        check(H5Tset_size(mem.get(), H5T_VARIABLE), "string size");
        check(H5Aread(attr.get(), mem.get(), v.data()), "cannot read attribute " + name);
        for (hssize_t i = 0; i < n; ++i) out += (i ? "\n" : "") + std::string(v[i] ? v[i] : "");
        H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, v.data());
        return out;
    }
    const size_t len = H5Tget_size(type.get());
    std::vector<char> buf(len * n + 1, '\0');
    check(H5Aread(attr.get(), type.get(), buf.data()), "cannot read attribute " + name);
    for (hssize_t i = 0; i < n; ++i) {
        const char* s = buf.data() + i * len;
        out += (i ? "\n" : "") + std::string(s, strnlen(s, len));
    }
    return out;
}

std::vector<double> readDoubleAttribute(hid_t obj, const std::string& name) {
    Handle attr(check(H5Aopen(obj, name.c_str(), H5P_DEFAULT), "cannot open attribute " + name));
    Handle space(check(H5Aget_space(attr.get()), "dataspace of attribute " + name));
    const hssize_t n = std::max<hssize_t>(H5Sget_simple_extent_npoints(space.get()), 1);
    std::vector<double> v(n);
    check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, v.data()), "cannot read attribute " + name);
    return v;
}

std::vector<double> readDataset(hid_t loc, const std::string& name, std::vector<hsize_t>& dims) {
    Handle ds(check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), "cannot open dataset " + name));
    Handle space(check(H5Dget_space(ds.get()), "dataspace of " + name));
    const int rank = H5Sget_simple_extent_ndims(space.get());
    dims.assign(std::max(rank, 0), 0);
    if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    hsize_t total = 1;
    for (hsize_t d : dims) total *= d;
    std::vector<double> v(total);
    if (total > 0)
        check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()),
              "cannot read dataset " + name);
    return v;
}

std::vector<double> readDatasetRows(hid_t loc, const std::string& name, hsize_t first,
                                    hsize_t count, std::vector<hsize_t>& dims) {
    Handle ds(check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), "cannot open dataset " + name));
    Handle space(check(H5Dget_space(ds.get()), "dataspace of " + name));
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 1) throw std::runtime_error("HDF5: dataset " + name + " has no rows");
    dims.assign(size_t(rank), 0);
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    if (first >= dims[0]) return {};
    std::vector<hsize_t> start(size_t(rank), 0), n = dims;
    start[0] = first;
    n[0] = std::min(count, dims[0] - first);
    hsize_t total = 1;
    for (hsize_t d : n) total *= d;
    std::vector<double> v(total);
    if (total == 0) return v;
    check(
        H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, n.data(), nullptr),
        "selection in " + name);
    Handle mem(check(H5Screate_simple(rank, n.data(), nullptr), "memory space"));
    check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, v.data()),
          "cannot read dataset " + name);
    return v;
}

}  // namespace io::h5

#pragma once
// Small RAII helpers over the HDF5 C API (serial HDF5 1.10) for the result writers and readers:
// owned handles, string and number attributes, datasets that grow along their first axis, and
// reading them back (bagsim report reads a run's results.h5).
// Every failure throws std::runtime_error naming the object; HDF5's own error printing is off
// (libraries print nothing).

#include <hdf5.h>

#include <string>
#include <vector>

namespace io::h5 {

/// An owned HDF5 identifier, closed with the right H5?close on destruction.
class Handle {
  public:
    Handle() = default;
    explicit Handle(hid_t id) : m_id(id) {}
    ~Handle() { reset(); }
    Handle(Handle&& o) noexcept : m_id(o.m_id) { o.m_id = H5I_INVALID_HID; }
    Handle& operator=(Handle&& o) noexcept {
        if (this != &o) {
            reset();
            m_id = o.m_id;
            o.m_id = H5I_INVALID_HID;
        }
        return *this;
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    hid_t get() const { return m_id; }
    bool isValid() const { return m_id >= 0; }
    void reset();

  private:
    hid_t m_id = H5I_INVALID_HID;
};

/// Turns off HDF5's automatic error printing on the default stack.
void silenceErrors();
/// Throws std::runtime_error("HDF5: <what>") if status < 0; returns status.
hid_t check(hid_t status, const std::string& what);

Handle createFile(const std::string& path);
Handle createGroup(hid_t loc, const std::string& name);

void setAttribute(hid_t obj, const std::string& name, const std::string& value);
void setAttribute(hid_t obj, const std::string& name, double value);
void setAttribute(hid_t obj, const std::string& name, int value);
void setAttribute(hid_t obj, const std::string& name, const std::vector<std::string>& values);
void setAttribute(hid_t obj, const std::string& name, const std::vector<double>& values);

/// Writes a whole fixed-size dataset of doubles or ints with the given dimensions.
void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const double* data, const std::string& unit);
void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const int* data, const std::string& unit);
/// float32 in the file (node positions for viewing).
void writeDataset(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const float* data, const std::string& unit);

/// Opens an existing file to write into it (a resumed run). @throws std::runtime_error.
Handle openFileReadWrite(const std::string& path);
/// Removes the link `name` from `loc` (the object goes once nothing links to it).
void deleteLink(hid_t loc, const std::string& name);
/// Opens a file read-only. @throws std::runtime_error (without the path) if it is not an HDF5
/// file or is locked.
Handle openFileReadOnly(const std::string& path);
/// True if `loc` has a link called `name` (one level; "mat", not "mat/time").
bool hasLink(hid_t loc, const std::string& name);
Handle openGroup(hid_t loc, const std::string& name);
bool hasAttribute(hid_t obj, const std::string& name);
/// A string attribute (fixed or variable length; the elements of an array joined by "\n").
std::string readStringAttribute(hid_t obj, const std::string& name);
/// A numeric attribute as doubles (a scalar gives one value).
std::vector<double> readDoubleAttribute(hid_t obj, const std::string& name);
/// A whole numeric dataset as doubles, row-major; `dims` receives its dimensions.
std::vector<double> readDataset(hid_t loc, const std::string& name, std::vector<hsize_t>& dims);
/// Rows [first, first + count) (along the first axis) of a numeric dataset as doubles,
/// row-major; `dims` receives the whole dataset's dimensions. Count is cut at the last row.
std::vector<double> readDatasetRows(hid_t loc, const std::string& name, hsize_t first,
                                    hsize_t count, std::vector<hsize_t>& dims);

/// A chunked dataset of rank 1 + inner.size() that grows along its first axis.
class GrowingDataset {
  public:
    GrowingDataset() = default;
    /// @param type H5T_NATIVE_DOUBLE, H5T_NATIVE_INT or H5T_NATIVE_INT8
    /// @param chunkRows rows per chunk
    GrowingDataset(hid_t loc, const std::string& name, hid_t type, std::vector<hsize_t> inner,
                   hsize_t chunkRows, const std::string& unit);
    /// Appends `rows` rows from data (row-major, rows * prod(inner) values of the memory type).
    void append(const void* data, hsize_t rows = 1);
    /// An existing dataset made by the constructor above, cut back to its first `rows` rows
    /// (a resumed run continues it). @throws std::runtime_error if it has fewer.
    static GrowingDataset open(hid_t loc, const std::string& name, hid_t type,
                               std::vector<hsize_t> inner, hsize_t rows);
    hsize_t getRows() const { return m_rows; }
    hid_t getId() const { return m_dataset.get(); }
    bool isValid() const { return m_dataset.isValid(); }

  private:
    Handle m_dataset;
    hid_t m_type = H5I_INVALID_HID;  // native memory type (not owned)
    std::vector<hsize_t> m_inner;
    hsize_t m_rows = 0;
    std::string m_name;
};

}  // namespace io::h5

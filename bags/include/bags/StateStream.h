#pragma once
/// @file Writing a simulation's state into a checkpoint and reading it back bit for bit: the
/// doubles as their bytes (never as decimal text), sizes checked on reading, each part opened
/// by a tag so that a checkpoint of another model (other bags, other controller) is refused
/// with a message naming the part instead of being read as garbage.
///
/// Every class that can be checkpointed offers saveState(StateWriter&) const and
/// loadState(StateReader&), which read exactly what the other wrote, in the same order. The
/// reader throws StateError on any mismatch (a tag, a size, the end of the data).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <cstring>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace bags {

/// A checkpoint that does not fit the model it is loaded into, or is cut short.
struct StateError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class StateWriter {
  public:
    /// A tag that loadState() checks: the part that follows.
    void tag(const std::string& name) { str(name); }
    template <class T>
    void pod(const T& v) {
        static_assert(std::is_trivially_copyable<T>::value, "plain data only");
        const char* p = reinterpret_cast<const char*>(&v);
        m_data.append(p, sizeof(T));
    }
    void str(const std::string& s) {
        pod(std::uint64_t(s.size()));
        m_data.append(s);
    }
    template <class T>
    void vec(const std::vector<T>& v) {
        pod(std::uint64_t(v.size()));
        for (const T& x : v) pod(x);
    }
    /// Any dense Eigen matrix (its sizes, then its coefficients, column-major).
    template <class M>
    void mat(const Eigen::DenseBase<M>& m) {
        pod(std::int64_t(m.rows()));
        pod(std::int64_t(m.cols()));
        for (Eigen::Index j = 0; j < m.cols(); ++j)
            for (Eigen::Index i = 0; i < m.rows(); ++i) pod(m(i, j));
    }
    void pose(const Eigen::Isometry3d& X) { mat(X.matrix()); }
    void rng(const std::mt19937_64& r) {
        std::ostringstream s;
        s << r;
        str(s.str());
    }
    const std::string& getData() const { return m_data; }

  private:
    std::string m_data;
};

class StateReader {
  public:
    explicit StateReader(std::string data) : m_data(std::move(data)) {}
    /// @throws StateError if the next part is not `name`.
    void tag(const std::string& name) {
        const std::string got = str();
        if (got != name)
            throw StateError("checkpoint: expected the part '" + name + "', found '" +
                             got.substr(0, 60) + "' (the checkpoint is of another model)");
    }
    /// True (and the tag read) if the next part is `name`; false, nothing read, otherwise or
    /// at the end: for a part a later writer added.
    bool readTagIf(const std::string& name) {
        const size_t at = m_pos;
        try {
            if (str() == name) return true;
        } catch (const StateError&) {
        }
        m_pos = at;
        return false;
    }
    template <class T>
    T pod() {
        static_assert(std::is_trivially_copyable<T>::value, "plain data only");
        need(sizeof(T));
        T v;
        std::memcpy(&v, m_data.data() + m_pos, sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    template <class T>
    void pod(T& v) {
        v = pod<T>();
    }
    std::string str() {
        const std::uint64_t n = pod<std::uint64_t>();
        need(n);
        std::string s = m_data.substr(m_pos, n);
        m_pos += n;
        return s;
    }
    template <class T>
    void vec(std::vector<T>& v) {
        const std::uint64_t n = pod<std::uint64_t>();
        need(n * sizeof(T));
        v.resize(n);
        for (T& x : v) pod(x);
    }
    /// A vector whose size the model fixes: a different size is a mismatch named by `what`.
    template <class T>
    void vecOfSize(std::vector<T>& v, size_t size, const char* what) {
        vec(v);
        if (v.size() != size) mismatch(what, v.size(), size);
    }
    template <class M>
    void mat(Eigen::PlainObjectBase<M>& m) {
        const std::int64_t r = pod<std::int64_t>(), c = pod<std::int64_t>();
        if (r < 0 || c < 0) throw StateError("checkpoint: a matrix of negative size");
        need(std::uint64_t(r) * std::uint64_t(c) * sizeof(typename M::Scalar));
        m.resize(r, c);
        for (Eigen::Index j = 0; j < c; ++j)
            for (Eigen::Index i = 0; i < r; ++i) m(i, j) = pod<typename M::Scalar>();
    }
    /// A matrix whose column count the model fixes.
    template <class M>
    void matOfCols(Eigen::PlainObjectBase<M>& m, Eigen::Index cols, const char* what) {
        mat(m);
        if (m.cols() != cols) mismatch(what, size_t(m.cols()), size_t(cols));
    }
    Eigen::Isometry3d pose() {
        Eigen::Matrix4d m;
        const std::int64_t r = pod<std::int64_t>(), c = pod<std::int64_t>();
        if (r != 4 || c != 4) throw StateError("checkpoint: a pose is not 4 x 4");
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) m(i, j) = pod<double>();
        Eigen::Isometry3d X;
        X.matrix() = m;
        return X;
    }
    void rng(std::mt19937_64& r) {
        std::istringstream s(str());
        s >> r;
        if (!s) throw StateError("checkpoint: a random generator's state cannot be read");
    }
    /// @throws StateError naming what differs.
    [[noreturn]] static void mismatch(const char* what, size_t got, size_t expected) {
        throw StateError(std::string("checkpoint: ") + what + ": " + std::to_string(got) +
                         " in the checkpoint, " + std::to_string(expected) +
                         " in the model (the checkpoint is of another model)");
    }
    bool atEnd() const { return m_pos == m_data.size(); }

  private:
    void need(std::uint64_t n) const {
        if (n > m_data.size() - m_pos)
            throw StateError("checkpoint: cut short (a part ends past the end of the data)");
    }
    std::string m_data;
    size_t m_pos = 0;
};

}  // namespace bags

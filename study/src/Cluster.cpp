#include "Cluster.h"

#include <cstdlib>

#ifdef BAGSIM_MPI
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>
#include <vector>
#endif

namespace study {

#ifdef BAGSIM_MPI

namespace {

enum Tag { kRequest = 1, kAssign = 2 };

/// A rank's request carries the previous case's index and record as bytes:
/// [int32 case][record text].
std::vector<char> pack(int c, const std::string& record) {
    std::vector<char> buf(sizeof(int) + record.size());
    std::memcpy(buf.data(), &c, sizeof(int));
    std::memcpy(buf.data() + sizeof(int), record.data(), record.size());
    return buf;
}

void pause() { std::this_thread::sleep_for(std::chrono::milliseconds(20)); }

class MpiCluster : public Cluster {
  public:
    MpiCluster() {
        MPI_Comm_rank(MPI_COMM_WORLD, &m_rank);
        MPI_Comm_size(MPI_COMM_WORLD, &m_size);
        m_busy.assign(m_size, false);
        m_stopped.assign(m_size, false);
    }
    ~MpiCluster() override { MPI_Finalize(); }

    int getRank() const override { return m_rank; }
    int getSize() const override { return m_size; }

    void poll(const std::function<int()>& next,
              const std::function<void(int, const std::string&)>& done) override {
        for (;;) {
            int flag = 0;
            MPI_Status st;
            MPI_Iprobe(MPI_ANY_SOURCE, kRequest, MPI_COMM_WORLD, &flag, &st);
            if (!flag) return;
            int bytes = 0;
            MPI_Get_count(&st, MPI_CHAR, &bytes);
            std::vector<char> buf(std::max(bytes, 1));
            MPI_Recv(buf.data(), bytes, MPI_CHAR, st.MPI_SOURCE, kRequest, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
            int c = -1;
            std::memcpy(&c, buf.data(), sizeof(int));
            m_busy[st.MPI_SOURCE] = false;
            if (c >= 0) done(c, std::string(buf.data() + sizeof(int), bytes - sizeof(int)));
            int assign = next();
            MPI_Send(&assign, 1, MPI_INT, st.MPI_SOURCE, kAssign, MPI_COMM_WORLD);
            if (assign < 0)
                m_stopped[st.MPI_SOURCE] = true;
            else
                m_busy[st.MPI_SOURCE] = true;
        }
    }

    int getNumBusy() const override {
        int n = 0;
        for (int r = 1; r < m_size; ++r) n += m_busy[r] ? 1 : 0;
        return n;
    }

    bool isAllStopped() const override {
        for (int r = 1; r < m_size; ++r)
            if (!m_stopped[r]) return false;
        return true;
    }

    int exchange(int previousCase, const std::string& record,
                 const std::function<bool()>& interrupted) override {
        std::vector<char> buf = pack(previousCase, record);
        MPI_Request send;
        MPI_Isend(buf.data(), static_cast<int>(buf.size()), MPI_CHAR, 0, kRequest, MPI_COMM_WORLD,
                  &send);
        int assign = -1;
        MPI_Request recv;
        MPI_Irecv(&assign, 1, MPI_INT, 0, kAssign, MPI_COMM_WORLD, &recv);
        for (;;) {
            int flag = 0;
            MPI_Test(&recv, &flag, MPI_STATUS_IGNORE);
            if (flag) break;
            if (interrupted()) {
                // Leave without the answer: rank 0 is stopping too.
                MPI_Cancel(&recv);
                MPI_Request_free(&recv);
                MPI_Request_free(&send);
                return -1;
            }
            pause();
        }
        MPI_Wait(&send, MPI_STATUS_IGNORE);
        return assign;
    }

  private:
    int m_rank = 0, m_size = 1;
    std::vector<bool> m_busy, m_stopped;
};

}  // namespace

std::unique_ptr<Cluster> joinCluster() {
    // Only under a launcher: a plain `bagsim study` of an MPI build runs alone, without MPI.
    if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMI_SIZE") &&
        !std::getenv("PMIX_RANK"))
        return nullptr;
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) MPI_Init(nullptr, nullptr);
    auto c = std::make_unique<MpiCluster>();
    if (c->getSize() < 2) return nullptr;  // finalises MPI
    return c;
}

#else

std::unique_ptr<Cluster> joinCluster() { return nullptr; }

#endif

}  // namespace study

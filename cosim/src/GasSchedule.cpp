#include "cosim/GasSchedule.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace cosim {

void GasSchedule::add(const std::vector<int>& bags, const GasCommand& command,
                      const std::string& name) {
    m_entries.push_back(Entry{bags, command, name});
}

void GasSchedule::validate(int numBags) const {
    std::map<std::pair<int, double>, std::string> starts;
    for (const Entry& e : m_entries) {
        auto fail = [&](const std::string& what) {
            throw std::invalid_argument("gas command " + e.name + ": " + what);
        };
        const GasCommand& c = e.command;
        if (!(c.time >= 0.0) || !std::isfinite(c.time)) {
            std::ostringstream s;
            s << "time " << c.time << " s; valid: 0 s or later";
            fail(s.str());
        }
        if (c.kind == GasCommand::Kind::Flow && !std::isfinite(c.massFlow))
            fail("mass flow is not finite; valid: a flow in kg/s (negative: out)");
        if (c.kind == GasCommand::Kind::Target &&
            !(c.targetMass > 0.0 && std::isfinite(c.targetMass) && c.rate > 0.0 &&
              std::isfinite(c.rate))) {
            std::ostringstream s;
            s << "target " << c.targetMass * 1e3 << " g at " << c.rate * 1e3
              << " g/s; valid: a positive mass and a positive rate";
            fail(s.str());
        }
        for (int b : e.bags) {
            if (b < 0 || b >= numBags)
                fail("bag " + std::to_string(b) + "; valid: 0 to " + std::to_string(numBags - 1));
            const auto key = std::make_pair(b, c.time);
            const auto it = starts.find(key);
            if (it != starts.end()) {
                std::ostringstream s;
                s << "bag " << b << " already has a command from " << c.time << " s (" << it->second
                  << "); valid: one command per bag and start time";
                fail(s.str());
            }
            starts.emplace(key, e.name);
        }
    }
}

const GasCommand* GasSchedule::findCommand(int bag, double t) const {
    const GasCommand* best = nullptr;
    for (const Entry& e : m_entries) {
        if (e.command.time > t) continue;
        bool holds = false;
        for (int b : e.bags) holds = holds || b == bag;
        if (holds && (!best || e.command.time >= best->time)) best = &e.command;
    }
    return best;
}

double GasSchedule::findNextChange(double t) const {
    double next = std::numeric_limits<double>::infinity();
    for (const Entry& e : m_entries)
        if (e.command.time > t) next = std::min(next, e.command.time);
    return next;
}

void GasSchedule::apply(double t, const std::vector<Bag*>& bags) const {
    for (int b = 0; b < int(bags.size()); ++b) {
        const GasCommand* c = bags[b] ? findCommand(b, t) : nullptr;
        if (!c) continue;
        Bag& bag = *bags[b];
        if (c->kind == GasCommand::Kind::Flow)
            bag.setMassFlow(c->massFlow);
        else
            bag.setTargetMass(c->targetMass, c->rate);
    }
}

}  // namespace cosim

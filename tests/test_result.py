"""One result: every problem kind answers with the common fields, one status label set."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

import contactqp as cq
from contactqp.core.local_problem import GlobalProblem, LocalProblem
from contactqp.core.result import ContactResult
from contactqp.core.status import STATUS_LABELS, ContactStatus, status_counts

SOURCE = Path(cq.__file__).parent
EXAMPLE = Path(__file__).parent.parent / "examples" / "problems" / "two_springs.toml"
R = np.array([[1.0e-6, 0.4e-6], [0.4e-6, 1.0e-6]])  # m/N


def frictionless():
    return cq.solve_gaps(R, loads=[1500.0, 500.0], gaps=[1e-3, 1e-3])


def frictional():
    block = cq.ReducedModel(
        stiffness=np.diag([2.0e6, 5.0e6]), dofs_per_node=2, coordinates=[[0.0, 0.0]]
    )
    floor = cq.PlaneObstacle(point=[0.0, 0.0], normal=[0.0, -1.0])
    return cq.solve(cq.FrictionalProblem(block, [400.0, -1000.0], [floor], mu=0.3))


def local():
    W = np.array([[2.0, 0.1, 0.0], [0.1, 1.0, 0.0], [0.0, 0.0, 1.0]])
    return cq.solve(LocalProblem(W, [-1.0, 0.5, 0.0], [0.3], 3))


def global_():
    M = np.array([[4.0, 1.0], [1.0, 3.0]])
    return cq.solve(GlobalProblem(M, np.eye(2), [1.0, -1.0], [-1.0, 0.0], [0.3], 2))


def fastened():
    k = 4  # two rows of 4 nodes, one freedom each; pair i = (i, k + i)
    lower = 1e-6 * (np.eye(k) + 0.3 * np.ones((k, k)))
    flexibility = np.block([[lower, np.zeros((k, k))], [np.zeros((k, k)), 2 * lower]])
    model = cq.ReducedModel(flexibility=flexibility, dofs_per_node=1)
    pairs = np.column_stack([np.arange(k), k + np.arange(k)])
    problem = cq.ContactProblem(
        model, np.zeros(2 * k), [cq.NodePairs(pairs, [1e-4, 2e-4, 1e-4, 3e-4])]
    )
    return cq.solve(cq.FastenedProblem(problem, [1]))


KINDS = {
    "frictionless": frictionless,
    "frictional": frictional,
    "local": local,
    "global": global_,
    "fastened": fastened,
}
CLASSES = {
    "frictionless": ContactResult,
    "frictional": cq.FrictionalResult,
    "local": cq.LocalResult,
    "global": cq.LocalResult,
    "fastened": cq.FastenedResult,
}


@pytest.fixture(scope="module", params=sorted(KINDS))
def kind_and_result(request):
    return request.param, KINDS[request.param]()


def test_every_result_has_the_common_fields_with_their_types(kind_and_result):
    kind, result = kind_and_result
    assert type(result) is CLASSES[kind] and isinstance(result, ContactResult)
    assert result.success is True and result.status == 0, result.message
    for name in ("displacements", "forces", "nodal_forces", "gaps", "contact_status"):
        assert isinstance(getattr(result, name), np.ndarray), name
    for name in ("displacements", "forces", "nodal_forces", "gaps"):
        assert getattr(result, name).dtype == float and np.all(np.isfinite(getattr(result, name)))
    k = result.n_contacts
    assert result.gaps.shape == (k,) and result.contact_status.shape == (k,) and k > 0
    assert result.forces.shape[0] in (k, result.forces.size)
    assert np.issubdtype(result.contact_status.dtype, np.integer)
    assert set(result.contact_status.tolist()) <= {int(s) for s in type(result).STATUSES}
    assert isinstance(result.energy, float)
    assert np.isfinite(result.energy) == (kind not in ("local", "global"))
    assert isinstance(result.status, int) and result.status in (0, 1, 2)
    assert isinstance(result.message, str) and result.message
    assert isinstance(result.iterations, int) and result.iterations >= 0
    assert isinstance(result.seconds, float) and result.seconds >= 0.0
    assert isinstance(result.method, str) and result.method
    assert isinstance(result.info, dict)
    certificate = result.certificate
    assert certificate.passed and certificate.finite and isinstance(certificate.worst, float)
    assert isinstance(certificate.as_dict(), dict) and certificate.as_dict()["passed"] is True


def test_summary_and_as_dict_agree(kind_and_result):
    _, result = kind_and_result
    summary, fields = result.summary(), result.as_dict()
    json.dumps(summary)  # no arrays
    for name in ("success", "status", "message", "method", "iterations", "seconds", "certificate"):
        assert summary[name] == fields[name], name
    assert summary["energy"] == fields["energy"] or np.isnan(summary["energy"])
    assert summary["contacts"] == result.n_contacts == len(result.status_labels)
    counts = status_counts(result.contact_status)
    assert {s.label: summary[s.label] for s in type(result).STATUSES} == {
        s.label: counts[s.label] for s in type(result).STATUSES
    }
    assert sum(summary[s.label] for s in type(result).STATUSES) == result.n_contacts
    assert set(result.status_labels) <= set(STATUS_LABELS)
    assert repr(result).startswith(type(result).__name__ + "(success=True")


def test_the_kinds_report_their_own_statuses():
    assert frictionless().status_labels == ["closed", "open"]
    assert frictional().status_labels == ["slip"]
    state = fastened()
    assert state.status_labels[1] == "fastened" and "fastened" not in state.status_labels[2:]
    assert local().status_labels[0] in ("stick", "slip")


def test_one_label_set_and_codes_as_the_files_have_them():
    assert STATUS_LABELS == ("open", "stick", "slip", "closed", "fastened")
    assert [int(s) for s in ContactStatus] == list(range(len(STATUS_LABELS)))
    assert all(STATUS_LABELS[s] == s.label for s in ContactStatus)


_WATCHED = {
    "open",
    "stick",
    "slip",
    "closed",
    "fastened",
    "contact",
    "fastener",
    "sliding",
    "sticking",
}


def test_no_module_defines_a_second_status_label_set():
    """A literal tuple, list or set holding two or more status words is a second definition of
    the labels; only core/status.py may spell them out (by the enum's names)."""
    found = []
    for path in SOURCE.rglob("*.py"):
        if path == SOURCE / "core" / "status.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
                words = {
                    e.value
                    for e in node.elts
                    if isinstance(e, ast.Constant) and isinstance(e.value, str)
                }
                if len(words & _WATCHED) >= 2:
                    found.append(f"{path.relative_to(SOURCE)}:{node.lineno} {sorted(words)}")
    assert not found, found


def test_statuses_written_by_a_problem_file_are_in_the_set(tmp_path):
    from contactqp.io.problem_file import load_problem_file, write_results

    spec = load_problem_file(EXAMPLE)
    result = spec.solve()
    write_results(spec, result, tmp_path)
    lines = (tmp_path / "contacts.csv").read_text().splitlines()
    column = lines[0].split(",").index("status")
    assert {line.split(",")[column] for line in lines[1:]} <= set(STATUS_LABELS)
    with np.load(tmp_path / "result.npz") as data:
        np.testing.assert_array_equal(data["contact_status"], result.contact_status)


def test_no_method_returns_a_bare_tuple():
    from contactqp.methods.lawson_hanson import NonnegativeQPSolution, solve_nonnegative_qp

    solution = solve_nonnegative_qp(np.array([[2.0, 0.5], [0.5, 1.0]]), np.array([1.0, -1.0]))
    assert isinstance(solution, NonnegativeQPSolution) and solution.converged
    np.testing.assert_allclose(solution.x, [0.5, 0.0])


def test_a_fastener_that_does_not_close_fails_the_verdict():
    contact = frictionless()  # contact 0 closed (gap 0), contact 1 open
    assert contact.gaps[1] > 1e-5 and abs(contact.gaps[0]) < 1e-15
    held = cq.FastenedResult.from_contact(contact, [0], [0.0], contact.forces, [1e-3, 1e-3])
    assert held.success and held.status == 0 and held.status_labels == ["fastened", "open"]
    loose = cq.FastenedResult.from_contact(contact, [1], [0.0], contact.forces, [1e-3, 1e-3])
    assert not loose.success and loose.status == 2 and "fastener closure failed" in loose.message
    assert loose.closure == pytest.approx(contact.gaps[1])
    assert contact.status_labels == ["closed", "open"]  # the contact result is left as it was

"""call_idempotent: the first answer of possibly several requests, and a clear error when none comes."""
import threading

import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from ros_helpers import ros_context
from sim_harness import wait_for
from std_srvs.srv import Trigger

from ur_common.spin_thread import SpinThread
from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.service_call import call_idempotent


def test_the_first_answer_is_returned_and_unanswered_requests_are_sent_again():
    with ros_context() as ctx:
        server, caller = Node('idem_server', context=ctx), Node('idem_caller', context=ctx)
        served = []
        release = threading.Event()

        def on_call(request, response):
            served.append(1)
            release.wait(5.0)  # the first answer is held back: the caller must send again meanwhile
            response.success, response.message = True, f'call {len(served)}'
            return response
        server.create_service(Trigger, 'idem', on_call)
        client = caller.create_client(Trigger, 'idem')
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(server)
        executor.add_node(caller)
        spinner = SpinThread(executor, 'idem').start()
        try:
            assert client.wait_for_service(timeout_sec=10.0)
            threading.Timer(0.35, release.set).start()
            answer = call_idempotent(client, Trigger.Request(), 'a test', timeout=10.0, resend=0.1)
            assert answer.success and answer.message == 'call 1'
            wait_for(lambda: len(served) >= 3, timeout=10.0, what='the requests sent meanwhile')  # 0, 0.1, 0.2 s...
        finally:
            release.set()
            spinner.stop()
            server.destroy_node()
            caller.destroy_node()


def test_no_answer_names_the_service_what_and_the_requests_sent():
    with ros_context() as ctx:
        node = Node('idem_alone', context=ctx)
        client = node.create_client(Trigger, '/nobody/here')
        with pytest.raises(ClientError, match=r'^/nobody/here: no answer to a test within 0\.3 s \([3-4] requests '
                                              r'sent\)$'):
            call_idempotent(client, Trigger.Request(), 'a test', timeout=0.3, resend=0.1)
        node.destroy_node()

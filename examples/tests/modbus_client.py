"""A Modbus/TCP client that no one here wrote (pymodbus) against the microcomputer-plc soft-PLC.

Usage: python3 modbus_client.py HOST PORT
Reads the images, forces the START input through its coil, and checks that the program reacts
(the motor output comes on), then releases the forcing and forces an output coil, then writes a
block of coils (function 15) and a block of registers (function 16) and sees every point act.
Exit code 0 when every check holds.
"""
import sys
import time

from pymodbus.client import ModbusTcpClient

MOTOR, GATE = 0, 2
STOP = 1
INPUT_COILS = 1000


def main():
    host, port = sys.argv[1], int(sys.argv[2])
    client = ModbusTcpClient(host, port=port, timeout=3)
    assert client.connect(), "cannot connect"

    def coils(address, count):
        r = client.read_coils(address, count=count)
        assert not r.isError(), r
        return r.bits[:count]

    def wait_for(what, check, seconds=5.0):
        end = time.time() + seconds
        while time.time() < end:
            if check():
                return
            time.sleep(0.05)
        raise AssertionError("timed out waiting for " + what)

    inputs = client.read_discrete_inputs(0, count=16)
    assert not inputs.isError(), inputs
    registers = client.read_input_registers(0, count=19)
    assert not registers.isError(), registers
    # 32-bit counters span two registers, high word first: cycles are 3-4.
    cycles_before = registers.registers[3] << 16 | registers.registers[4]
    assert cycles_before > 0, "the PLC is cycling"

    # Stop the belt by forcing STOP, then see the motor go off.
    assert not client.write_coil(INPUT_COILS + STOP, True).isError()
    wait_for("motor off while STOP is forced", lambda: not coils(MOTOR, 1)[0])
    assert coils(INPUT_COILS + STOP, 1)[0], "the forced input is visible"

    # Release all forcing (holding register 0 <- 1), force START: the program starts the motor.
    assert not client.write_register(0, 1).isError()
    time.sleep(0.3)
    assert not client.write_coil(INPUT_COILS + 0, True).isError()
    wait_for("motor on after START is forced", lambda: coils(MOTOR, 1)[0])

    # Force an output coil: the reject gate opens whatever the program says.
    assert not client.write_coil(GATE, True).isError()
    wait_for("gate forced open", lambda: coils(GATE, 1)[0])

    # A block of coils (function 15) forces every coil it names, also one written with the value
    # it shows: outputs 0 and 2 forced on, then both visible as forced (discrete inputs 100-115).
    shown = coils(MOTOR, 3)
    assert not client.write_coils(MOTOR, [True, shown[1], True]).isError()
    wait_for(
        "outputs 0-2 forced by write_coils",
        lambda: client.read_discrete_inputs(100, count=3).bits[:3] == [True, True, True],
    )
    # A block of registers (function 16): 0 <- 0 nothing, 1 <- 1 releases output 1, 2 <- 0 input 0.
    assert not client.write_registers(0, [0, 1, 0]).isError()
    wait_for(
        "output 1 released by write_registers",
        lambda: client.read_discrete_inputs(100, count=3).bits[:3] == [True, False, True],
    )
    wait_for("input 0 released", lambda: not client.read_discrete_inputs(200, count=1).bits[0])

    registers = client.read_input_registers(0, count=19)
    assert (registers.registers[3] << 16 | registers.registers[4]) > cycles_before, "cycles went on"
    client.close()
    print("modbus end-to-end: ok")


if __name__ == "__main__":
    main()

"""CANopen slave of the simulated motors (MIS manual §11): DS-301, DSP-402, LSS over python-can.
"""

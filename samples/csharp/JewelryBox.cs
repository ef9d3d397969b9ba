// A minimal C# console host (Mono or .NET): the paper's jewelry box, one right hand arriving open at the lid's lip,
// closing its pinch there and swinging the lid open about the hinge over two seconds at 60 Hz; prints the lid angle
// every 10 frames.
//   mcs -out:JewelryBox.exe bindings/csharp/Handsim.cs samples/csharp/JewelryBox.cs
//   LD_LIBRARY_PATH=<dir of libhandsim.so> mono JewelryBox.exe
using System;
using Handsim;

static class JewelryBoxSample
{
    static int Main()
    {
        const double dt = 1.0 / 60.0;
        using (var world = new World())
        {
            JewelryBox box = world.BuildJewelryBox();
            var hand = new TrackedHand(world.AddHand(HandDef.Default), HandSide.Right);  // the frame names its hand
            HandPoseParams pinch = HandPoseParams.LidPinch;
            Console.WriteLine("frame  time_s  hand_deg  lid_deg  grasped");
            for (int i = 0; i <= 140; ++i)
            {
                // The hand closes its pinch over 0.25 s as people do (the default grasp rule grasps only a closing
                // hand), then from frame 20 it swings to 80 degrees over 2 s.
                double t = i < 20 ? 0.0 : Math.Min((i - 20) / 120.0, 1.0);
                double handAngle = t * 80.0 * Math.PI / 180.0;
                Hands.MakeFrame(HandSide.Right, world.LidPinchPalm(box, HandSide.Right, handAngle), pinch.Closing(i * dt),
                                hand.Joints);
                world.StepHands(dt, hand);
                if (i % 10 == 0)
                    Console.WriteLine(string.Format("{0,5}  {1,6:F3}  {2,8:F2}  {3,7:F2}  {4}", i, (i + 1) * dt, handAngle * 180.0 / Math.PI,
                                                    world.JointState(box.Hinge).Value * 180.0 / Math.PI,
                                                    world.BodyGrasp(box.Lid).Grasped ? "yes" : "no"));
            }
            Console.WriteLine("state_hash 0x" + world.StateHash.ToString("x16"));
        }
        return 0;
    }
}
